"""Section 2.4 benchmark of [1]_: three bearing models on one dynamic load.

Set-up (paper Table 1): L = 17.2 mm, D = 101.55 mm, c = 0.0975 mm,
mu = 0.0391 Pa s, 500 rpm, initial eccentricity ratio (0.0997, 0.0071),
time step 1e-4 s.  The paper gives its load (Fig. 4) only as a plot, so a
load of similar character is defined here and kept fixed:
:func:`benchmark_load`.  The paper does not state its run length either; the
timed run is one revolution at 500 rpm, 0.12 s = 1200 steps.

Paper Table 2 (MATLAB, same time step): mobility ~7 s, Method 1 ~129 s,
FDM 320 x 40 ~43 560 s.  Speed targets here (one core, compiled, no
compile time): mobility <= 10 ms, Method 1 <= 100 ms, FDM 320 x 40 <= 5 s.
They are printed, never asserted by the tests.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2.4, Tables 1-2, Figs. 4-5.
"""
from __future__ import annotations

import contextlib
import io
import math
import os
import statistics
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from gerotor_twin.bearing.registry import make_bearing
from gerotor_twin.bearing.geometry import TABLE1, BearingGeometry
from gerotor_twin.bearing.simulate import simulate
from gerotor_twin.errors import InputError, check_range

__all__ = ["benchmark_load", "run_benchmark", "BenchmarkResult", "MethodTiming", "format_table",
           "plot_trajectories", "compare_with_ross", "RossComparison", "BENCH_RPM",
           "BENCH_EPS0", "BENCH_DT", "PAPER_TIMES_S", "TARGET_TIMES_S", "BENCH_METHODS"]

BENCH_RPM = 500.0                      #: journal speed [rpm] (Table 1)
BENCH_OMEGA = BENCH_RPM * 2.0 * math.pi / 60.0   #: [rad/s]
BENCH_EPS0 = (0.0997, 0.0071)          #: initial eccentricity ratio [-] (Table 1)
BENCH_DT = 1e-4                        #: time step [s] (Table 2)
BENCH_METHODS = ("mobility", "short", "fdm")
PAPER_TIMES_S = {"mobility": 7.0, "short": 129.0, "fdm": 43560.0}   #: Table 2 [s]
TARGET_TIMES_S = {"mobility": 0.010, "short": 0.100, "fdm": 5.0}    #: ours, one revolution [s]
LABELS = {"mobility": "Mobility method", "short": "Method 1 (short bearing)",
          "fdm": "FDM"}

# Benchmark load [N] as a function of the shaft angle th = omega t (one period per
# revolution): a mean load of 1.5 kN towards -y (the delivery-side chamber pressure), a
# first-harmonic part of 1 kN that swings the load direction by about +-57 deg, and a
# 7th-harmonic ripple (one pulse per chamber of a 7-chamber pump) of 200/300 N.
# |F| spans 0.53 - 2.74 kN, direction -147 deg .. -33 deg.
_LOAD_MEAN_Y = -1500.0
_LOAD_H1_X, _LOAD_H1_Y = 1000.0, -1000.0
_LOAD_H7_X, _LOAD_H7_Y = 200.0, 300.0


def benchmark_load(t):
    """Dynamic load of the sec. 2.4 benchmark (stand-in for Fig. 4 of [1]_).

    .. math::

        F_x = 1000 \\sin\\vartheta + 200 \\sin 7\\vartheta ,\\qquad
        F_y = -1500 - 1000 \\cos\\vartheta + 300 \\cos 7\\vartheta ,\\qquad
        \\vartheta = \\omega t,\\ \\omega = 500\\ \\mathrm{rpm}

    Parameters
    ----------
    t : float or array_like
        Time [s].

    Returns
    -------
    numpy.ndarray
        Load on the journal [N], shape (2,) for scalar ``t``, else (len(t), 2).
    """
    th = BENCH_OMEGA * np.asarray(t, dtype=float)
    fx = _LOAD_H1_X * np.sin(th) + _LOAD_H7_X * np.sin(7.0 * th)
    fy = _LOAD_MEAN_Y + _LOAD_H1_Y * np.cos(th) + _LOAD_H7_Y * np.cos(7.0 * th)
    return np.stack([fx, fy], axis=-1)


@dataclass(frozen=True)
class MethodTiming:
    """Wall time of one method on the timed run.

    Attributes
    ----------
    method : str
        Model name.
    median_s : float
        Median wall time [s] of ``runs_s``.
    runs_s : tuple of float
        Individual wall times [s] (compile excluded: warmed up first).
    n_steps : int
        Time steps of the timed run [-].
    paper_s : float
        Paper Table 2 time [s] (MATLAB, run length not stated).
    target_s : float
        Our target [s].
    """

    method: str
    median_s: float
    runs_s: tuple
    n_steps: int
    paper_s: float
    target_s: float

    @property
    def meets_target(self) -> bool:
        return self.median_s <= self.target_s


@dataclass(frozen=True)
class BenchmarkResult:
    """Everything the sec. 2.4 benchmark produced.

    Attributes
    ----------
    timings : dict
        ``method -> MethodTiming``.
    trajectories : dict
        ``method -> BearingTrajectory`` over ``revolutions`` revolutions.
    max_difference : dict
        ``"a vs b" -> max_t |e_a - e_b| / c`` [-] over those trajectories.
    grid : tuple of int
        FDM grid ``(nx, ny)``.
    revolutions : float
        Length of the trajectory runs [rev].
    geometry : BearingGeometry
        Bearing used.
    """

    timings: dict
    trajectories: dict
    max_difference: dict
    grid: tuple
    revolutions: float
    geometry: BearingGeometry = field(default=TABLE1)

    def to_dict(self) -> dict:
        """JSON-ready summary (no trajectories)."""
        return {
            "rpm": BENCH_RPM, "dt_s": BENCH_DT, "eps0": list(BENCH_EPS0),
            "fdm_grid": list(self.grid), "revolutions_plotted": self.revolutions,
            "timed_run": "one revolution at 500 rpm = 1200 steps",
            "methods": {m: {"median_s": t.median_s, "runs_s": list(t.runs_s),
                            "n_steps": t.n_steps, "paper_matlab_s": t.paper_s,
                            "target_s": t.target_s, "meets_target": t.meets_target,
                            "max_eccentricity_ratio":
                                float(self.trajectories[m].eccentricity_ratio.max()),
                            "contact_events": len(self.trajectories[m].events)}
                        for m, t in self.timings.items()},
            "max_difference_over_c": dict(self.max_difference),
        }


def _parse_methods(methods) -> tuple:
    if isinstance(methods, str):
        methods = [m.strip() for m in methods.split(",") if m.strip()]
    methods = tuple(methods)
    bad = [m for m in methods if m not in BENCH_METHODS]
    if bad or not methods:
        raise InputError("methods", ",".join(methods), "comma-separated subset of "
                         + ",".join(BENCH_METHODS))
    return methods


def run_benchmark(methods=BENCH_METHODS, grid: tuple = (320, 40), repeats: int = 3,
                  revolutions: float = 3.0, geometry: BearingGeometry = TABLE1,
                  timed_revolutions: float = 1.0) -> BenchmarkResult:
    """Run, time and compare the bearing models on :func:`benchmark_load`.

    Parameters
    ----------
    methods : sequence of str or str
        Subset of ``("mobility", "short", "fdm")`` (or ``"mobility,short"``).
    grid : tuple of int
        FDM grid ``(nx, ny)`` [-].
    repeats : int
        Timed runs per method [-], 1..50; the median is reported.
    revolutions : float
        Length of the trajectory (plot) runs [rev], > 0.
    geometry : BearingGeometry
        Bearing (default paper Table 1).
    timed_revolutions : float
        Length of the timed run [rev] (default 1 = 1200 steps).

    Returns
    -------
    BenchmarkResult
    """
    methods = _parse_methods(methods)
    if isinstance(repeats, bool) or not isinstance(repeats, (int, np.integer)) \
            or not 1 <= repeats <= 50:
        raise InputError("repeats", repeats, "integer in [1, 50]")
    revolutions = check_range("revolutions", revolutions, 0.0, 100.0, lo_open=True, unit="rev")
    timed_revolutions = check_range("timed_revolutions", timed_revolutions, 0.0, 100.0,
                                    lo_open=True, unit="rev")
    period = 2.0 * math.pi / BENCH_OMEGA
    e0 = geometry.clearance_m * np.asarray(BENCH_EPS0)
    timings, trajectories = {}, {}
    for name in methods:
        opts = {"nx": grid[0], "ny": grid[1]} if name == "fdm" else {}
        model = make_bearing(name, geometry, **opts)
        simulate(model, e0, benchmark_load, BENCH_OMEGA, BENCH_DT, 10 * BENCH_DT)  # compile
        runs = []
        traj = None
        for _ in range(repeats):
            t0 = time.perf_counter()
            traj = simulate(model, e0, benchmark_load, BENCH_OMEGA, BENCH_DT,
                            timed_revolutions * period)
            runs.append(time.perf_counter() - t0)
        timings[name] = MethodTiming(name, statistics.median(runs), tuple(runs),
                                     len(traj.t) - 1, PAPER_TIMES_S[name], TARGET_TIMES_S[name])
        trajectories[name] = simulate(model, e0, benchmark_load, BENCH_OMEGA, BENCH_DT,
                                      revolutions * period)
    diffs = {}
    for i, a in enumerate(methods):
        for b in methods[i + 1:]:
            d = trajectories[a].e - trajectories[b].e
            diffs[f"{a} vs {b}"] = float(np.max(np.hypot(d[:, 0], d[:, 1]))
                                         / geometry.clearance_m)
    return BenchmarkResult(timings, trajectories, diffs, tuple(grid), revolutions, geometry)


def format_table(result: BenchmarkResult) -> str:
    """Table-2-like text: paper MATLAB times beside ours, targets, differences."""
    lines = [
        "Journal-bearing benchmark (paper sec. 2.4): Table 1 bearing, 500 rpm, dt = 1e-4 s,",
        "eps0 = (0.0997, 0.0071); timed run = one revolution (1200 steps), median wall time,",
        "compile excluded.  Paper times: MATLAB, Table 2 (run length not stated).",
        "",
        f"{'method':<28}{'paper [s]':>12}{'ours [s]':>12}{'speed-up':>11}{'target [s]':>12}  met",
    ]
    for name, t in result.timings.items():
        label = LABELS[name] + (f" {result.grid[0]}x{result.grid[1]}" if name == "fdm" else "")
        lines.append(f"{label:<28}{t.paper_s:>12.6g}{t.median_s:>12.4g}"
                     f"{t.paper_s / t.median_s:>10.3g}x{t.target_s:>12.4g}  "
                     f"{'yes' if t.meets_target else 'NO'}")
    lines.append("")
    lines.append(f"Max distance between trajectories over {result.revolutions:g} rev "
                 "(fraction of the clearance c):")
    for pair, d in result.max_difference.items():
        lines.append(f"  {pair:<22}{d:.4f}")
    for name, tr in result.trajectories.items():
        lines.append(f"  {name:<10} max eps = {tr.eccentricity_ratio.max():.4f}, "
                     f"min film = {tr.min_film_thickness.min() * 1e6:.2f} um, "
                     f"contact events: {len(tr.events)}")
    return "\n".join(lines)


def plot_trajectories(result: BenchmarkResult, path) -> None:
    """Save the load (cf. Fig. 4 of [1]_) and the journal-centre trajectories
    inside the clearance circle (cf. Fig. 5) to ``path`` (PNG/PDF/SVG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_load, ax_traj) = plt.subplots(1, 2, figsize=(12, 5.4))
    t = np.linspace(0.0, 2.0 * math.pi / BENCH_OMEGA, 721)
    f = benchmark_load(t)
    deg = np.degrees(BENCH_OMEGA * t)
    ax_load.plot(deg, f[:, 0], label="$F_x$")
    ax_load.plot(deg, f[:, 1], label="$F_y$")
    ax_load.plot(deg, np.hypot(f[:, 0], f[:, 1]), "k--", label="$|F|$")
    ax_load.set_xlabel("shaft angle [deg]")
    ax_load.set_ylabel("load on the journal [N]")
    ax_load.set_title("Benchmark load (one revolution, 500 rpm)")
    ax_load.grid(True, alpha=0.3)
    ax_load.legend()

    phi = np.linspace(0.0, 2.0 * math.pi, 361)
    ax_traj.plot(np.cos(phi), np.sin(phi), "k-", lw=1.0, label="clearance circle")
    some = next(iter(result.trajectories.values()))
    ax_traj.plot(some.eps_max * np.cos(phi), some.eps_max * np.sin(phi), "k:", lw=0.8,
                 label=f"contact limit eps = {some.eps_max:g}")
    c = result.geometry.clearance_m
    styles = {"mobility": "-", "short": "--", "fdm": "-."}
    for name, tr in result.trajectories.items():
        label = LABELS[name] + (f" {result.grid[0]}x{result.grid[1]}" if name == "fdm" else "")
        ax_traj.plot(tr.e[:, 0] / c, tr.e[:, 1] / c, styles[name], lw=1.3, label=label)
    ax_traj.plot(BENCH_EPS0[0], BENCH_EPS0[1], "ko", ms=4, label="start")
    ax_traj.set_aspect("equal")
    ax_traj.set_xlabel(r"$\varepsilon_x = e_x / c$")
    ax_traj.set_ylabel(r"$\varepsilon_y = e_y / c$")
    ax_traj.set_title(f"Journal-centre trajectories ({result.revolutions:g} rev)")
    ax_traj.grid(True, alpha=0.3)
    ax_traj.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


@dataclass(frozen=True)
class RossComparison:
    """One static FDM pressure solve against ross-rotordynamics' ``FluidFlow``.

    Attributes
    ----------
    eps : float
        Eccentricity ratio [-].
    grid : tuple of int
        ``(nx, ny)``; ross uses ``ntheta = nx + 1`` (closed circle), ``nz = ny``.
    ours_n, ross_n : tuple of float
        ``(radial, tangential, magnitude)`` film force [N].
    ours_s, ross_s : float
        Wall time of one static solve + force [s].
    """

    eps: float
    grid: tuple
    ours_n: tuple
    ross_n: tuple
    ours_s: float
    ross_s: float

    @property
    def load_difference(self) -> float:
        """``|F_ours| / |F_ross| - 1`` [-]."""
        return self.ours_n[2] / self.ross_n[2] - 1.0

    def __str__(self) -> str:
        return (f"static FDM solve vs ross-rotordynamics FluidFlow, eps = {self.eps:g}, "
                f"grid {self.grid[0]}x{self.grid[1]}:\n"
                f"  ours: F_r = {self.ours_n[0]:.4g} N, F_t = {self.ours_n[1]:.4g} N, "
                f"|F| = {self.ours_n[2]:.4g} N, {self.ours_s * 1e3:.3g} ms\n"
                f"  ross: F_r = {self.ross_n[0]:.4g} N, F_t = {self.ross_n[1]:.4g} N, "
                f"|F| = {self.ross_n[2]:.4g} N, {self.ross_s * 1e3:.4g} ms\n"
                f"  load difference {100 * self.load_difference:+.2f} %, "
                f"time ratio ross/ours = {self.ross_s / self.ours_s:.3g}")


@contextlib.contextmanager
def _quiet_fds():
    """Silence stdout/stderr at the file-descriptor level (ross pulls in CoolProp, whose
    C++ core prints a REFPROP warning on import)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()):
                yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])


def compare_with_ross(grid: tuple = (320, 40), eps: float = 0.6,
                      geometry: BearingGeometry = TABLE1) -> RossComparison | None:
    """Compare one static FDM solve with ross-rotordynamics (optional dependency).

    ross's ``FluidFlow`` solves the Reynolds equation of the annulus on the
    same kind of grid (dense matrix, ``spsolve``, negative pressure clipped).
    Returns ``None`` and prints ``ross-rotordynamics not installed`` when
    the package is absent (it is a benchmark-only extra, not a runtime
    dependency).

    Parameters
    ----------
    grid : tuple of int
        ``(nx, ny)`` [-]; ross needs a dense ``(nx+1)ny`` square matrix
        (1.3 GB at 320 x 40).
    eps : float
        Eccentricity ratio [-], 0 < eps < 1.
    geometry : BearingGeometry
        Bearing.

    Returns
    -------
    RossComparison or None
    """
    eps = check_range("eps", eps, 0.0, 1.0, lo_open=True, hi_open=True)
    try:
        with _quiet_fds():
            from ross.bearings.fluid_flow import FluidFlow
            from ross.bearings.fluid_flow_coefficients import calculate_oil_film_force
    except Exception as exc:  # noqa: BLE001 - ImportError or a broken install
        print(f"ross-rotordynamics not installed (or not importable: {type(exc).__name__}); "
              "skipping the ross comparison.  Optional: pip install ross-rotordynamics")
        return None
    g = geometry
    c = g.clearance_m
    nx, ny = grid
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        ff = FluidFlow(ny, nx + 1, g.length_m, BENCH_OMEGA, 0.0, 0.0, g.radius_m, g.radius_m + c,
                       g.viscosity_pa_s, 860.0, eccentricity=eps * c, attitude_angle=0.7,
                       bearing_type="medium_size",
                       immediately_calculate_pressure_matrix_numerically=True)
        fr, ft, _, _ = calculate_oil_film_force(ff, force_type="numerical")
    ross_s = time.perf_counter() - t0
    model = make_bearing("fdm", g, nx=nx, ny=ny)
    e = np.array([eps * c, 0.0])
    model.film_force(e, np.zeros(2), BENCH_OMEGA)  # compile
    runs = []
    for _ in range(5):
        t0 = time.perf_counter()
        f = model.film_force(e, np.zeros(2), BENCH_OMEGA)
        runs.append(time.perf_counter() - t0)
    ours = (-f[0], f[1], float(np.hypot(*f)))   # e along +x: radial = -F_x, tangential = F_y
    return RossComparison(eps, (nx, ny), ours, (fr, ft, math.hypot(fr, ft)),
                          statistics.median(runs), ross_s)
