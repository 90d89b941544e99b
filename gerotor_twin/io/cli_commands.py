"""``gerotor-twin log recover``: a finalised, indexed copy of an unfinalised MCAP log.

::

    gerotor-twin log recover FILE [-o OUT] [-f]     # one file -> FILE.recovered.mcap (or OUT)
    gerotor-twin log recover DIR                    # every unfinalised log of a crashed run in DIR

Unreadable input (missing, empty, not MCAP) prints one line and exits 2.
"""
from __future__ import annotations

from pathlib import Path

from gerotor_twin.errors import InputError

__all__ = ["add_parser"]


def add_parser(subparsers) -> None:
    """Add ``log recover`` to an argparse sub-parser set."""
    log = subparsers.add_parser("log", help="MCAP log tools (recover)")
    sub = log.add_subparsers(dest="log_command", required=True)
    r = sub.add_parser("recover", help="finalised, indexed copy of an unfinalised MCAP (crash, disk full)",
                       description="Copy every valid record of an MCAP file that was never finalised "
                                   "(process killed, power cut, disk full) into a new, finalised and "
                                   "indexed file that ros2 bag, Foxglove and rosbags open. The original "
                                   "is not modified. Given a directory: every unfinalised log in it "
                                   "that no live process is writing and that has no recovered copy yet.")
    r.add_argument("file", help="MCAP file, or a log directory")
    r.add_argument("-o", "--output", help="output file (default: FILE with .recovered.mcap)")
    r.add_argument("-f", "--force", action="store_true", help="replace an existing output file")
    r.add_argument("--compression", default="zstd", choices=("zstd", "lz4", "none"),
                   help="chunk compression of the output (default zstd)")
    r.set_defaults(func=_cmd_recover)


def _cmd_recover(args) -> int:
    from gerotor_twin.io.reader import McapReadError
    from gerotor_twin.io.recover import recover, unfinalised_logs

    src = Path(args.file)
    if src.is_dir():
        if args.output:
            raise InputError("--output", args.output, "no output file when FILE is a directory")
        files = unfinalised_logs(src)
        if not files:
            print(f"{src}: no unfinalised MCAP log to recover")
            return 0
    else:
        files = [src]
    failed = 0
    for f in files:
        try:
            rep = recover(f, args.output, overwrite=args.force, compression=args.compression)
        except McapReadError as exc:
            if len(files) == 1:
                raise InputError(str(exc.path), "(file)", "an MCAP file", exc.what) from None
            print(f"error: {exc}")
            failed += 1
            continue
        state = "finalised already; re-indexed" if rep.source_complete else "unfinalised"
        print(f"recovered ({state}) {rep.summary()}")
    return 2 if failed else 0
