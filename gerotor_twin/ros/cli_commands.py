"""``gerotor-twin node`` (run the twin node) and ``gerotor-twin bench node`` (node benchmark).

:func:`add_parser` adds ``node`` to the project's sub-parsers and teaches the
existing ``bench`` sub-command the choice ``node``; rclpy is imported only
when one of them runs.
"""
from __future__ import annotations

import argparse

__all__ = ["add_parser"]


def add_parser(subparsers) -> None:
    """Add ``node`` and ``bench node`` to an argparse sub-parser set."""
    n = subparsers.add_parser(
        "node", help="run the ROS 2 twin node (same as `twin_node`); pass --ros-args ... after it",
        description="Run twin_node. Everything after `node` goes to ROS, e.g. "
                    "`gerotor-twin node --ros-args --params-file config/twin.yaml`.")
    n.add_argument("ros_args", nargs=argparse.REMAINDER, help="--ros-args ...")
    n.set_defaults(func=_cmd_node)

    from ..cli import extend_bench
    bench = extend_bench(subparsers, "node", "; node: twin node startup, CPU, RTF, latency, input accounting")
    if bench is None:
        return
    bench.add_argument("--node-model", default="mobility", help="bench node: outer-gear model")
    bench.add_argument("--node-rpms", default=None,
                       help="bench node: comma-separated speeds [rpm] (default: the pump's top speed, "
                            "range.max_speed_rpm of --config); --config F: the node runs that pump (pump_config), "
                            "--bar: its delivery pressure (default range.max_delivery_bar)")
    bench.add_argument("--node-seconds", type=float, default=4.0, help="bench node: run time per speed [s]")
    bench.add_argument("--node-rate", type=float, default=1000.0,
                       help="bench node: input rate of the separate publisher process, per input [Hz]")
    bench.add_argument("--node-busy", type=int, default=0,
                       help="bench node: CPU-bound processes to run beside it (a loaded machine)")
    bench.add_argument("--node-repeats", type=int, default=1,
                       help="bench node: runs per speed, each with a fresh node (> 1: a median line too; the "
                            "node CPU varies by several points between starts)")
    bench.add_argument("--node-param", action="append", metavar="NAME:=VALUE",
                       help="bench node: extra twin_node parameter (repeatable)")
    previous = bench.get_default("func")

    def dispatch(args):
        if args.what == "node":
            from gerotor_twin.ros.bench_node import cmd_bench_node
            return cmd_bench_node(args)
        return previous(args)

    bench.set_defaults(func=dispatch)


def _cmd_node(args) -> int:
    from gerotor_twin.ros.node import main
    rest = list(args.ros_args)
    return main(["twin_node", *rest])
