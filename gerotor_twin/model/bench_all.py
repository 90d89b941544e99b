"""``gerotor-twin bench all``: the figures of docs/performance.md, as one markdown block, in one run.

One run times the default pump (both compiled gear models at 1000 / 2000 / 3000 rpm and its rated
pressure) and every pump of the family at its top speed and both ends of its delivery pressure
(:func:`.bench.realtime`, :func:`.bench.family_realtime`), optionally the first compile of the
numba kernels on a fresh cache, and writes one markdown block with the date, the commit, the
command, the machine and its load.  ``--write-doc F`` replaces the block between
:data:`BEGIN` and :data:`END` of ``F`` in place, so a rerun updates the doc.  Figures are printed
and written, never asserted in tests.
"""
from __future__ import annotations

import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["BEGIN", "END", "Machine", "BenchAll", "machine", "git_commit", "first_compile", "run_all",
           "markdown", "replace_block", "write_doc"]

BEGIN = "<!-- bench all: begin -->"   #: the first line of the generated block in a doc
END = "<!-- bench all: end -->"       #: its last line

_ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Machine:
    """Where the figures were measured.

    Attributes
    ----------
    cpu : str
        CPU model name (``/proc/cpuinfo``, else :func:`platform.processor`).
    cores : int
        Logical cores the OS reports.
    system : str
        OS and kernel release.
    python, numba : str
        Interpreter and numba versions.
    """

    cpu: str
    cores: int
    system: str
    python: str
    numba: str


@dataclass
class BenchAll:
    """The result of one ``bench all`` run.

    Attributes
    ----------
    date : str
        UTC date and time of the start, ``YYYY-MM-DD HH:MM``.
    commit : str
        Short commit of the tree (``+ uncommitted changes`` when dirty), or ``unknown``.
    command : str
        The command line that produced it.
    machine : Machine
        Where it ran.
    load : tuple of float
        1-minute load average before and after the run.
    default_rows : list of dict
        :func:`.bench.realtime` rows of the default pump (``pump`` key added).
    family_rows : list of dict
        :func:`.bench.realtime` rows of the family (``pump`` key added).
    compile : dict or None
        ``{"seconds": float, "line": str}`` of :func:`first_compile`, None when not run.
    """

    date: str
    commit: str
    command: str
    machine: Machine
    load: tuple
    default_rows: list = field(default_factory=list)
    family_rows: list = field(default_factory=list)
    compile: dict | None = None


def _cpu_model() -> str:
    """The CPU's model name from ``/proc/cpuinfo``; :func:`platform.processor` where there is none."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def machine() -> Machine:
    """The :class:`Machine` this process runs on."""
    try:
        import numba
        numba_version = numba.__version__
    except ImportError:                                   # pragma: no cover - numba is a dependency
        numba_version = "not installed"
    return Machine(cpu=_cpu_model(), cores=os.cpu_count() or 1, system=f"{platform.system()} {platform.release()}",
                   python=platform.python_version(), numba=numba_version)


def git_commit(root: Path = _ROOT) -> str:
    """Short commit of the git tree at ``root``, with ``+ uncommitted changes`` when it differs from it.

    Returns ``unknown`` outside a git tree (an installed wheel).
    """
    def git(*args):
        return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=20)
    try:
        head = git("rev-parse", "--short", "HEAD")
        if head.returncode != 0:
            return "unknown"
        dirty = git("status", "--porcelain", "--untracked-files=no").stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head.stdout.strip() + (" + uncommitted changes" if dirty else "")


def first_compile() -> dict:
    """Time ``python -m gerotor_twin.precompile`` in a fresh process on an empty ``NUMBA_CACHE_DIR``.

    Returns
    -------
    dict
        ``seconds``: wall time of the process; ``line``: the line it printed (what it compiled).
    """
    with tempfile.TemporaryDirectory(prefix="gerotor_compile_") as tmp:
        env = dict(os.environ, NUMBA_CACHE_DIR=tmp)
        t0 = time.perf_counter()
        res = subprocess.run([sys.executable, "-m", "gerotor_twin.precompile"], env=env, capture_output=True,
                             text=True, check=True)
        seconds = time.perf_counter() - t0
    lines = [ln.strip() for ln in res.stdout.splitlines() if ln.strip()]
    return {"seconds": seconds, "line": lines[-1] if lines else ""}


def run_all(config, pumps, seconds: float = 1.0, repeats: int = 3, with_compile: bool = False,
            command: str = "gerotor-twin bench all", out=print) -> BenchAll:
    """Run the benchmarks of docs/performance.md.

    Parameters
    ----------
    config : PumpConfig
        The default pump (timed with ``mobility`` and ``fixed`` at 1000 / 2000 / 3000 rpm, its top pressure).
    pumps : sequence of FamilyPump
        The family (:func:`.family.family_pumps`), each timed with ``mobility`` at its top speed and both ends
        of its delivery pressure.
    seconds, repeats : float, int
        Simulated seconds per timed run and runs per point (the median is reported).
    with_compile : bool
        Also time the first compile (:func:`first_compile`, minutes).
    command : str
        The command line, written into the block.
    out : callable
        Where progress lines go.

    Returns
    -------
    BenchAll
    """
    from .bench import family_realtime, realtime

    start = datetime.datetime.now(datetime.timezone.utc)
    result = BenchAll(date=start.strftime("%Y-%m-%d %H:%M"), commit=git_commit(), command=command,
                      machine=machine(), load=(os.getloadavg()[0],))
    if with_compile:
        out("first compile on an empty numba cache (python -m gerotor_twin.precompile) ...")
        result.compile = first_compile()
        out(f"  {result.compile['seconds']:.1f} s: {result.compile['line']}")
    rows = realtime(config, models=("mobility", "fixed"), speeds=(1000, 2000, 3000),
                    bar=config.range.max_delivery_bar, seconds=seconds, repeats=repeats, out=out)
    result.default_rows = [dict(r, pump="default (config/pump.yaml)") for r in rows]
    for pump in pumps:
        out(f"{pump.name} ({pump.path}):")
        rows = family_realtime(pump.config, models=("mobility",), seconds=seconds, repeats=repeats, out=out)
        result.family_rows += [dict(r, pump=pump.name) for r in rows]
    result.load = (result.load[0], os.getloadavg()[0])
    return result


def _row(r: dict) -> str:
    """One markdown table row of a :func:`.bench.realtime` row with its ``pump``."""
    return (f"| {r['pump']} | {r['model']} | {r['rpm']:.0f} | {r['bar']:g} | {r['real_time_factor']:.2f} | "
            f"{r['cpu_real_time_factor']:.2f} | {r['substeps_per_revolution']:.0f} | {r['us_per_substep']:.2f} |")


def markdown(result: BenchAll, seconds: float, repeats: int) -> str:
    """The block docs/performance.md includes: provenance, machine, one table, between :data:`BEGIN` and :data:`END`.

    Parameters
    ----------
    result : BenchAll
    seconds, repeats : float, int
        What each point was timed over (stated in the block).

    Returns
    -------
    str
        The block, ending in a newline.
    """
    m = result.machine
    lines = [
        BEGIN,
        f"Measured {result.date} UTC at commit {result.commit}: `{result.command}`. Machine: {m.cpu}, "
        f"{m.cores} logical cores, {m.system}, Python {m.python}, numba {m.numba}; 1-minute load average "
        f"{result.load[0]:.1f} at the start, {result.load[-1]:.1f} at the end"
        + (" (other jobs were running: figures of a loaded machine)." if max(result.load) > 0.5 * m.cores else "."),
        "",
    ]
    if result.compile is not None:
        lines += [f"First compile on an empty numba cache (`python -m gerotor_twin.precompile`): "
                  f"{result.compile['seconds']:.0f} s ({result.compile['line'].rstrip('.')}).", ""]
    lines += [
        f"Model alone, one core; each point the median of {repeats} runs of {seconds:g} s simulated after a warm-up. "
        "RTF: simulated / wall time; CPU RTF: simulated / CPU time; µs/sub-step: wall time per ROS2 sub-step "
        "attempted (accepted and rejected), the output steps' own work included.",
        "",
        "| pump | model | rpm | bar | RTF | CPU RTF | sub-steps/rev | µs/sub-step |",
        "|---|---|---|---|---|---|---|---|",
        *(_row(r) for r in result.default_rows + result.family_rows),
        END,
    ]
    return "\n".join(lines) + "\n"


def replace_block(text: str, block: str) -> str:
    """``text`` with its part from the line :data:`BEGIN` to the line :data:`END` replaced by ``block``.

    Raises
    ------
    ValueError
        ``text`` does not hold exactly one :data:`BEGIN` followed by one :data:`END`.
    """
    if text.count(BEGIN) != 1 or text.count(END) != 1 or text.index(BEGIN) > text.index(END):
        raise ValueError(f"expected one '{BEGIN}' line followed by one '{END}' line")
    head, _, rest = text.partition(BEGIN)
    _, _, tail = rest.partition(END)
    return head + block.rstrip("\n") + tail


def write_doc(path, block: str) -> None:
    """Replace the generated block of the markdown file ``path`` by ``block`` (:func:`replace_block`)."""
    path = Path(path)
    path.write_text(replace_block(path.read_text(encoding="utf-8"), block), encoding="utf-8")
