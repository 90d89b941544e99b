"""Private ROS_DOMAIN_ID picker (behaviour tier: no DDS needed)."""
import socket

from gerotor_twin.ros import domain as D


def test_claimed_domains_are_in_the_linux_safe_range_and_distinct():
    got = [D.claim_domain() for _ in range(5)]
    try:
        assert len(set(got)) == 5
        assert all(1 <= d <= 101 for d in got)          # 0 (everyone's default) avoided
    finally:
        for d in got:
            D.release_domain(d)


def test_a_domain_with_a_bound_participant_port_is_skipped():
    d = D.claim_domain(seed=1)
    D.release_domain(d)
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        s.bind(("127.0.0.1", 7400 + 250 * d + 10))       # participant 0's unicast discovery port
        again = D.claim_domain(seed=1)                  # same probe order: d would come first
        assert again != d
        D.release_domain(again)
    finally:
        s.close()
