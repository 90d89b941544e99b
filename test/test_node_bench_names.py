"""twin_node beside a bench that has its own topic names: the README's recipe, run (behaviour, real processes).

The node runs as a subprocess on a private ``ROS_DOMAIN_ID`` with the bench's input names given as
parameters (``shaft_speed_topic``, ``delivery_pressure_topic``) and one output remapped with ROS's
``-r``; a bench peer in this process publishes only on the bench's names and listens on the remapped
output.  No wall-clock time is asserted.
"""
import math
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from gerotor_twin.io import messages as m  # noqa: E402
from gerotor_twin.ros.domain import claim_domain  # noqa: E402
from ros_peer import Peer, kill_node, start_node, stop_node  # noqa: E402

pytestmark = pytest.mark.slow

W = 1500 * math.pi / 30
PD = 101325.0 + 15e5
SPEED, PRESSURE, FLOW = "rig/pump/speed", "rig/pump/p_out", "rig/twin/flow"


def _bench_side(peer: Peer) -> list:
    """Point the peer's speed and pressure publishers at the bench's names; collect the remapped output."""
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import FluidPressure, JointState
    from std_msgs.msg import Float64
    peer.pubs["shaft_speed"] = peer.node.create_publisher(JointState, SPEED, qos_profile_sensor_data)
    peer.pubs["delivery_pressure"] = peer.node.create_publisher(FluidPressure, PRESSURE, qos_profile_sensor_data)
    flows = []
    peer.node.create_subscription(Float64, FLOW, lambda data, _info: flows.append(data), 10, raw=True)
    return flows


def test_node_follows_the_bench_names_and_remapped_outputs(tmp_path):
    """Inputs on the bench's own topics (parameters) drive the model; ``-r`` moves an output to the bench's
    namespace and nothing is published under the old name."""
    d = claim_domain()
    proc = start_node(d, tmp_path, f"shaft_speed_topic:={SPEED}", f"delivery_pressure_topic:={PRESSURE}",
                      remaps=(f"twin/delivery_flow:={FLOW}",))
    peer = Peer(d)
    try:
        flows = _bench_side(peer)
        peer.wait_matched(proc=proc)
        deadline = time.monotonic() + 30.0
        while len(flows) < 20 or not peer.get("twin/flow_summary"):
            assert time.monotonic() < deadline, "no output from the node on the bench's names"
            assert proc.poll() is None, "node exited"
            t = time.time_ns()
            peer.send("shaft_speed", W, t)
            peer.send("delivery_pressure", PD, t)
            time.sleep(0.005)
        assert stop_node(proc) == 0
    finally:
        kill_node(proc)
        peer.close()
    assert peer.get("twin/delivery_flow") == []
    from gerotor_twin.io.decode import decode
    assert all(decode(m.FLOAT64, raw).data > 0 for raw in flows[-5:])
