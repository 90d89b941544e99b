"""Benchmark figures as markdown blocks that a doc includes and a rerun replaces in place.

``gerotor-twin bench all`` times the default pump (both compiled gear models at 1000 / 2000 /
3000 rpm and its rated pressure) and every pump of the family at its top speed and both ends of
its delivery pressure (:func:`.bench.realtime`, :func:`.bench.family_realtime`), the wall time per
revolution of the four outer-gear models (:func:`.bench.models_cost`), optionally the first compile
of the numba kernels on a fresh cache, and writes one block (the tables of docs/performance.md).  ``gerotor-twin bench accuracy`` writes its points as a block too
(:func:`accuracy_markdown`, the table of docs/numerics.md).  Each block opens with the date, the
commit, the command, the machine and its load (:class:`Provenance`); ``--write-doc F`` replaces
the block between the markers of its name (:func:`markers`) in ``F``.  Figures are printed and
written, never asserted in tests.
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

__all__ = ["markers", "BEGIN", "END", "Machine", "Provenance", "BenchAll", "machine", "git_commit", "provenance",
           "first_compile", "run_all", "markdown", "accuracy_markdown", "replace_block", "write_doc"]


def markers(name: str) -> tuple[str, str]:
    """The first and last line of the generated block ``name`` in a doc (``"bench all"``, ``"bench accuracy"``)."""
    return f"<!-- {name}: begin -->", f"<!-- {name}: end -->"


BEGIN, END = markers("bench all")   #: the lines around the block of ``bench all``

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
class Provenance:
    """Where, when and how figures were measured.

    Attributes
    ----------
    date : str
        UTC date and time of the start, ``YYYY-MM-DD HH:MM``.
    commit : str
        Short commit of the tree (``+ uncommitted changes`` when dirty), or ``unknown``.
    command : str
        The command line that produced them.
    machine : Machine
        Where it ran.
    load : tuple of float
        1-minute load average at the start and, once :meth:`finish` ran, at the end.
    """

    date: str
    commit: str
    command: str
    machine: Machine
    load: tuple

    def finish(self) -> "Provenance":
        """Record the load at the end of the run; returns ``self``."""
        self.load = (self.load[0], os.getloadavg()[0])
        return self

    def sentence(self) -> str:
        """One markdown line: date, commit, command, machine, load (and whether the machine was loaded)."""
        m = self.machine
        loaded = max(self.load) > 0.5 * m.cores
        return (f"Measured {self.date} UTC at commit {self.commit}: `{self.command}`. Machine: {m.cpu}, "
                f"{m.cores} logical cores, {m.system}, Python {m.python}, numba {m.numba}; 1-minute load average "
                f"{self.load[0]:.1f} at the start, {self.load[-1]:.1f} at the end"
                + (" (other jobs were running: figures of a loaded machine)." if loaded else "."))


def provenance(command: str) -> Provenance:
    """The :class:`Provenance` of a run of ``command`` starting now (the end load follows from :meth:`finish`)."""
    start = datetime.datetime.now(datetime.timezone.utc)
    return Provenance(date=start.strftime("%Y-%m-%d %H:%M"), commit=git_commit(), command=command,
                      machine=machine(), load=(os.getloadavg()[0],))


@dataclass
class BenchAll:
    """The result of one ``bench all`` run.

    Attributes
    ----------
    provenance : Provenance
        Date, commit, command, machine and load.
    default_rows : list of dict
        :func:`.bench.realtime` rows of the default pump (``pump`` key added).
    family_rows : list of dict
        :func:`.bench.realtime` rows of the family (``pump`` key added).
    model_rows : list of dict
        :func:`.bench.models_cost` rows of the default pump.
    compile : dict or None
        ``{"seconds": float, "line": str}`` of :func:`first_compile`, None when not run.
    """

    provenance: Provenance
    default_rows: list = field(default_factory=list)
    family_rows: list = field(default_factory=list)
    model_rows: list = field(default_factory=list)
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
    """Run the benchmarks of docs/performance.md: real time of the default pump and the family, the gear models' cost.

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
    from .bench import family_realtime, models_cost, realtime

    result = BenchAll(provenance=provenance(command))
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
    result.model_rows = models_cost(config, bar=config.range.max_delivery_bar, revolutions=repeats, out=out)
    result.provenance.finish()
    return result


def _row(r: dict) -> str:
    """One markdown table row of a :func:`.bench.realtime` row with its ``pump``."""
    return (f"| {r['pump']} | {r['model']} | {r['rpm']:.0f} | {r['bar']:g} | {r['real_time_factor']:.2f} | "
            f"{r['cpu_real_time_factor']:.2f} | {r['substeps_per_revolution']:.0f} | {r['us_per_substep']:.2f} |")


def _model_row(r: dict) -> str:
    """One markdown table row of a :func:`.bench.models_cost` row."""
    rel = f"{r['relative_to_mobility']:.2f}" if r.get("relative_to_mobility") else "–"
    return (f"| {r['model']} | {r['rpm']:.0f} | {1e3 * r['wall_s_per_rev']:.2f} ms | {rel} | "
            f"{r['real_time_factor']:.3g} |")


def markdown(result: BenchAll, seconds: float, repeats: int) -> str:
    """The block docs/performance.md includes, between :data:`BEGIN` and :data:`END`: provenance and machine, the
    first compile (if timed), the real-time table, the gear models' cost (if timed).

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
    lines = [BEGIN, result.provenance.sentence(), ""]
    if result.compile is not None:
        lines += [f"First compile on an empty numba cache (`python -m gerotor_twin.precompile`, the mobility and "
                  f"fixed-centre models): {result.compile['seconds']:.0f} s of wall time; it printed "
                  f"`{result.compile['line']}`.", ""]
    lines += [
        f"Model alone, one core; each point the median of {repeats} runs of {seconds:g} s simulated after a warm-up. "
        "RTF: simulated / wall time; CPU RTF: simulated / CPU time; µs/sub-step: wall time per ROS2 sub-step "
        "attempted (accepted and rejected), the output steps' own work included.",
        "",
        "| pump | model | rpm | bar | RTF | CPU RTF | sub-steps/rev | µs/sub-step |",
        "|---|---|---|---|---|---|---|---|",
        *(_row(r) for r in result.default_rows + result.family_rows),
    ]
    if result.model_rows:
        lines += ["", "The four outer-gear models of the default pump at its rated pressure (as `bench models`: wall "
                  f"time per simulated revolution, timed over {repeats} revolutions from the mobility model's "
                  "periodic state; RTF: simulated / wall time):", "",
                  "| gear model | rpm | wall time / rev | × mobility | RTF |", "|---|---|---|---|---|",
                  *(_model_row(r) for r in result.model_rows)]
    lines.append(END)
    return "\n".join(lines) + "\n"


def _pct(x: float, digits: int = 2, sign: bool = False) -> str:
    """``x`` (a fraction) in percent as the docs write it: ``0.23 %``, ``+1.05 %``."""
    return f"{100 * x:{'+' if sign else ''}.{digits}f} %"


def accuracy_markdown(rows, prov: Provenance) -> str:
    """The block of ``bench accuracy`` points (:func:`.accuracy.print_accuracy` rows) for docs/numerics.md.

    Parameters
    ----------
    rows : list of dict
        One per point: model, rpm, bar and the figures of :func:`.accuracy.accuracy`, ``within_budget``.
    prov : Provenance

    Returns
    -------
    str
        The block between the markers of ``"bench accuracy"``, ending in a newline.
    """
    begin, end = markers("bench accuracy")
    lines = [begin, prov.sentence(), "",
             "Range: the reference's highest minus lowest chamber pressure; RMS and max: chamber-pressure error of "
             "that range; peak: the model's peak output against the reference's, of its gauge peak; sampled: the "
             "waveform's maximum at the output angles, = the solver's error there + what the output grid misses "
             "between them; η: volumetric efficiency, relative; flow RMS: of the mean delivery flow.", "",
             "| model | rpm | bar | range | RMS | max | peak | sampled (solver + grid) | η | flow RMS | "
             "sub-steps/rev | verdict |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['rpm']:.0f} | {r['bar']:g} | {r['pressure_range'] / 1e5:.1f} bar | "
            f"{_pct(r['rms_pressure_error_of_range'])} | {_pct(r['max_pressure_error_of_range'], 1)} | "
            f"{_pct(r['peak_pressure_error_gauge'], sign=True)} | {_pct(r['sampled_peak_error'], sign=True)} "
            f"({_pct(r['peak_numerics_error'], sign=True)} {_pct(r['peak_sampling_error'], sign=True)}) | "
            f"{_pct(r['efficiency_error'], 3, sign=True)} | {_pct(r['flow_rms_error'])} | "
            f"{r['substeps_per_revolution']:.0f} | {'ok' if r['within_budget'] else 'outside'} |")
    lines.append(end)
    return "\n".join(lines) + "\n"


def replace_block(text: str, block: str, name: str = "bench all") -> str:
    """``text`` with its part from the begin line to the end line of ``name`` (:func:`markers`) replaced by ``block``.

    Raises
    ------
    ValueError
        ``text`` does not hold exactly one begin line followed by one end line of ``name``.
    """
    begin, end = markers(name)
    if text.count(begin) != 1 or text.count(end) != 1 or text.index(begin) > text.index(end):
        raise ValueError(f"expected one '{begin}' line followed by one '{end}' line")
    head, _, rest = text.partition(begin)
    _, _, tail = rest.partition(end)
    return head + block.rstrip("\n") + tail


def write_doc(path, block: str, name: str = "bench all") -> None:
    """Replace the generated block ``name`` of the markdown file ``path`` by ``block`` (:func:`replace_block`)."""
    path = Path(path)
    path.write_text(replace_block(path.read_text(encoding="utf-8"), block, name), encoding="utf-8")
