"""The command line imports only the module of the command given (behaviour)."""
import argparse
import importlib
import subprocess
import sys
from pathlib import Path

from gerotor_twin import cli

ROOT = Path(__file__).resolve().parent.parent


def _subparsers(parser):
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))   # noqa: SLF001


def _bench_choices(sub):
    return next(a.choices for a in sub.choices["bench"]._actions if a.dest == "what")      # noqa: SLF001


def test_the_command_table_is_what_the_modules_register():
    """Behaviour: each module of ``_COMMAND_MODULES``, given the parser of the commands defined in ``cli``, adds
    exactly the commands ``_COMMAND_OF`` names for it, and extends ``bench`` only if it is in ``_BENCH_MODULES``; a
    command the table does not know (or a module the table sends to that does not register it) fails here."""
    built_in = _subparsers(cli.build_parser(["geometry"]))
    assert sorted(built_in.choices) == sorted(cli._BUILT_IN)
    for name in cli._COMMAND_MODULES:
        sub = _subparsers(cli.build_parser(["geometry"]))
        before, bench_before = set(sub.choices), _bench_choices(sub)
        importlib.import_module(name).add_parser(sub)
        assert set(sub.choices) - before == {c for c, m in cli._COMMAND_OF.items() if m == name}, name
        assert (_bench_choices(sub) != bench_before) == (name in cli._BENCH_MODULES), name
    assert set(cli._COMMAND_OF.values()) | set(cli._BENCH_MODULES) == set(cli._COMMAND_MODULES)


def test_a_command_line_parses_as_with_every_command():
    """Behaviour: the parser built for a command line gives the namespace the parser of every command gives (the
    command's function the same by name: a module's dispatcher is a closure made by each ``add_parser``)."""
    def parsed(parser, argv):
        ns = vars(parser.parse_args(argv))
        return {**ns, "func": ns["func"].__qualname__}
    for argv in (["simulate", "--rpm", "1000", "--bar", "5"], ["bench", "maps", "--jobs", "1"],
                 ["health", "twin.mcap", "--json", "a.json"], ["log", "recover", "x.mcap"], ["geometry"]):
        assert parsed(cli.build_parser(argv), argv) == parsed(cli.build_parser(), argv), argv


def test_a_command_line_imports_only_its_command():
    """Behaviour: a command answers without importing the other commands' modules (≈ 1.3 s of a 1.7 s start,
    docs/performance.md): ``simulate`` with a missing config file none of them, nor matplotlib or scipy.stats;
    ``health`` with a missing recording not even numba.  Each answers with its one line and exit 2."""
    others = ("gerotor_twin.report.build", "gerotor_twin.calibration.command", "gerotor_twin.offline.run_bag",
              "gerotor_twin.offline.sweep", "gerotor_twin.bench_emulator.cli_commands", "matplotlib", "scipy.stats")
    for argv, absent, line in (
            (["simulate", "--rpm", "1000", "--bar", "5", "--config", "/nonexistent/pump.yaml"], others,
             "error: --config = '/nonexistent/pump.yaml' is invalid"),
            (["health", "/nonexistent/twin.mcap"], others + ("numba",), "error: /nonexistent/twin.mcap")):
        code = (f"import sys\nfrom gerotor_twin.cli import main\nrc = main({argv!r})\n"
                f"print(rc, [m for m in {absent!r} if m in sys.modules])")
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
        assert p.stdout.strip() == "2 []", (argv, p.stdout, p.stderr)
        assert p.stderr.startswith(line), p.stderr
