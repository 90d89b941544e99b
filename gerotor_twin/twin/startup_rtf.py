"""Start-up real-time check: the pump model's real-time factor on this machine at its hardest points (no ROS).

Before the twin follows a bench it can tell whether this machine runs the
configured pump model fast enough: :func:`measure` advances the model (the
configured outer-gear model, in the twin's sample cells) at the pump's top
speed (``range.max_speed_rpm``) and at both ends of its delivery pressure, the
ends of the family's operating grid (:func:`gerotor_twin.model.family.pressure_extremes`:
``range.max_delivery_bar`` and 2 bar, or 10 % of it if lower), each from a state that has run
:data:`SETTLE_REVOLUTIONS` revolutions, and times :data:`REVOLUTIONS`
revolutions; the whole measurement stops early when it has used
:data:`BUDGET_S` of wall time (at least one cell is always timed per point).
The slowest point is the figure (:attr:`StartupRtf.worst`).

Real-time factor (RTF) = simulated time / wall time of this thread; the CPU
figure (simulated / CPU time of this thread) tells a slow model from a busy
machine.  Below the threshold, :meth:`StartupRtf.status` is a WARN status
``gerotor_twin: real time`` (it stays WARN for the life of the twin: the
measurement is not repeated); :class:`~gerotor_twin.twin.core.TwinCore`
keeps the result and adds that status to every ``/diagnostics``.

Cost: on the default pump (mobility, 3000 rpm) 2 × 7 revolutions of 20 ms,
≈ 0.05 s of wall time (docs/node.md has the figures); a model slower than real time is cut at
:data:`BUDGET_S` (≈ 1 s) plus at most one cell per phase.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

from gerotor_twin.errors import check_range
from gerotor_twin.io import messages as m
from gerotor_twin.model.pump import Inputs, PumpModel, PumpState
from gerotor_twin.units import pa_abs_to_bar_gauge, rad_s_to_rpm

__all__ = ["RtfPoint", "StartupRtf", "measure", "operating_points", "STATUS_NAME", "DEFAULT_THRESHOLD",
           "MAX_THRESHOLD", "BUDGET_S", "SETTLE_REVOLUTIONS", "REVOLUTIONS"]

STATUS_NAME = "gerotor_twin: real time"
#: Default WARN threshold of the node (``startup_rtf_threshold``, its description says why 1.5).
DEFAULT_THRESHOLD = 1.5
#: Largest threshold accepted [-] (a check that always warns).
MAX_THRESHOLD = 1000.0
#: Wall time the whole measurement may take [s] (settling included).
BUDGET_S = 1.0
#: Revolutions run before timing, from the model's initial state [-].
SETTLE_REVOLUTIONS = 2
#: Revolutions timed per operating point [-].
REVOLUTIONS = 5


@dataclass(frozen=True)
class RtfPoint:
    """The real-time factor at one operating point.

    Parameters
    ----------
    omega : float
        Shaft speed [rad/s].
    p_delivery : float
        Delivery pressure, absolute [Pa].
    p_atm : float
        Atmospheric pressure of the config (for the gauge figure) [Pa].
    simulated_s : float
        Model time timed [s].
    wall_s : float
        Wall time it took [s].
    cpu_s : float
        CPU time of the measuring thread meanwhile [s].
    settled_s : float
        Model time run before timing [s].
    """

    omega: float
    p_delivery: float
    p_atm: float
    simulated_s: float
    wall_s: float
    cpu_s: float
    settled_s: float

    @property
    def rtf(self) -> float:
        """Simulated time / wall time [-] (inf if the wall time was not measurable)."""
        return self.simulated_s / self.wall_s if self.wall_s > 0 else math.inf

    @property
    def cpu_rtf(self) -> float:
        """Simulated time / CPU time of the measuring thread [-]."""
        return self.simulated_s / self.cpu_s if self.cpu_s > 0 else math.inf

    @property
    def speed_rpm(self) -> float:
        return rad_s_to_rpm(self.omega)

    @property
    def delivery_bar(self) -> float:
        """Delivery pressure, gauge [bar]."""
        return pa_abs_to_bar_gauge(self.p_delivery, self.p_atm)

    @property
    def revolutions(self) -> float:
        """Revolutions timed [-]."""
        return self.simulated_s * self.omega / (2 * math.pi)

    def label(self) -> str:
        return f"{self.speed_rpm:.0f} rpm / {self.delivery_bar:.3g} bar"


@dataclass(frozen=True)
class StartupRtf:
    """Result of :func:`measure`: the points, the threshold, the cost.

    Parameters
    ----------
    points : tuple of RtfPoint
        One per operating point, in the order measured.
    threshold : float
        WARN below this real-time factor [-] (0: never).
    bearing_model : str
        The outer-gear model measured.
    cost_s : float
        Wall time of the whole measurement, settling included [s].
    """

    points: tuple[RtfPoint, ...]
    threshold: float
    bearing_model: str
    cost_s: float

    @property
    def worst(self) -> RtfPoint:
        """The point with the lowest real-time factor."""
        return min(self.points, key=lambda p: p.rtf)

    @property
    def below(self) -> bool:
        """True when the worst real-time factor is below a (positive) threshold."""
        return self.threshold > 0 and self.worst.rtf < self.threshold

    def summary(self) -> str:
        """One line for the log: every point, the worst first, the threshold and the cost."""
        pts = sorted(self.points, key=lambda p: p.rtf)
        return (f"start-up real-time check ({self.bearing_model} model, {self.cost_s:.2f} s): "
                + ", ".join(f"RTF {p.rtf:.3g} at {p.label()} (CPU-time RTF {p.cpu_rtf:.3g})" for p in pts)
                + f"; threshold {self.threshold:g}")

    def message(self) -> str:
        """The status message: ``ok`` or why the twin may not keep real time."""
        w = self.worst
        if not self.below:
            return f"ok: model runs at RTF {w.rtf:.3g} at {w.label()} on this machine (threshold {self.threshold:g})"
        head = f"model runs at RTF {w.rtf:.2g} at {w.label()} on this machine"
        if w.rtf < 1.0:
            why = "the twin cannot keep real time"
        else:
            why = f"below the margin startup_rtf_threshold = {self.threshold:g}: the twin may not keep real time"
        busy = (f" (CPU-time RTF {w.cpu_rtf:.2g}: the machine is busy)" if w.cpu_rtf >= self.threshold else "")
        return (f"{head}: {why}{busy}; expect lag and skipped backlog at that speed; "
                f"use a faster outer-gear model (bearing_model, now {self.bearing_model}), a faster or idle "
                f"machine, or run below that speed")

    def values(self) -> dict:
        """Key/values of the status (units in the names)."""
        w = self.worst
        return {"startup_rtf": round(w.rtf, 4), "startup_rtf_cpu": round(w.cpu_rtf, 4),
                "startup_rtf_speed_rad_s": round(w.omega, 4), "startup_rtf_speed_rpm": round(w.speed_rpm, 2),
                "startup_rtf_delivery_pa": round(w.p_delivery, 1),
                "startup_rtf_delivery_bar": round(w.delivery_bar, 4),
                "startup_rtf_threshold": self.threshold, "startup_rtf_bearing_model": self.bearing_model,
                "startup_rtf_cost_s": round(self.cost_s, 4),
                "startup_rtf_points": "; ".join(f"{p.label()}: RTF {p.rtf:.3g} (CPU {p.cpu_rtf:.3g}, "
                                                f"{p.revolutions:.3g} rev)" for p in self.points)}

    def status(self) -> dict:
        """``diagnostic_msgs/DiagnosticStatus`` dict: WARN when :attr:`below`, else OK."""
        level = m.DIAG_WARN if self.below else m.DIAG_OK
        return m.diagnostic_status(level, STATUS_NAME, self.message(), hardware_id="gerotor_twin",
                                   values=self.values())


def operating_points(model: PumpModel) -> list[Inputs]:
    """The points measured: top speed at the lowest and the highest delivery pressure.

    Speed and pressures: :func:`~gerotor_twin.model.family.speed_extremes` (the
    highest) and :func:`~gerotor_twin.model.family.pressure_extremes` (both), the
    operating grid the family's numerics are checked on; the low pressure never
    below the suction pressure.  In ``restriction`` mode (delivery pressure a
    state) one point.

    Returns
    -------
    list of Inputs
        Shaft speed [rad/s], suction and delivery pressure [Pa absolute], reference oil temperature.
    """
    from gerotor_twin.model.family import pressure_extremes, speed_extremes
    from gerotor_twin.units import bar_gauge_to_pa_abs, rpm_to_rad_s
    cfg = model.config
    w = rpm_to_rad_s(speed_extremes(cfg)[1])
    ps, p_atm = cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa
    low, high = (bar_gauge_to_pa_abs(b, p_atm) for b in pressure_extremes(cfg))
    lows = [max(low, ps)] if not model.restriction_mode else []
    return [model.check_inputs(Inputs(w, ps, p)) for p in (*lows, high)]


def _run(model: PumpModel, st: PumpState, inputs: Inputs, span_s: float, chunk_s: float,
         stop: Callable[[], bool]) -> PumpState:
    """Advance ``st`` by ``span_s`` [s] in cells of ``chunk_s`` [s], at least one, until ``stop()``."""
    end = st.t + span_s
    while True:
        st, _ = model.advance(st, min(chunk_s, end - st.t), inputs)
        if end - st.t <= 1e-12 or stop():
            return st


def measure(model: PumpModel, threshold: float = DEFAULT_THRESHOLD, *, chunk_s: float = 0.005,
            budget_s: float = BUDGET_S, settle_revolutions: float = SETTLE_REVOLUTIONS,
            revolutions: float = REVOLUTIONS, timer: Callable[[], float] = time.perf_counter,
            cpu_timer: Callable[[], float] = time.thread_time) -> StartupRtf:
    """Real-time factor of ``model`` on this machine at :func:`operating_points`.

    Parameters
    ----------
    model : PumpModel
        The twin's model (compiled: call it once before, or the JIT is timed).
    threshold : float
        WARN below this real-time factor, in [0, :data:`MAX_THRESHOLD`] [-]; 0 = never (the figures
        are still measured).
    chunk_s : float
        Model time per ``advance`` call: the twin's sample period [s].
    budget_s : float
        Wall time the whole measurement may take, settling included [s]; each
        point gets an equal share, half of it for settling.  At least one cell
        is settled and one timed per point whatever the budget.
    settle_revolutions, revolutions : float
        Revolutions run before timing and timed, per point [-].
    timer, cpu_timer : callable
        Wall clock and CPU clock of this thread [s].

    Returns
    -------
    StartupRtf
    """
    check_range("startup_rtf_threshold", threshold, 0.0, MAX_THRESHOLD)
    check_range("chunk_s", chunk_s, 0.0, 1.0, lo_open=True, unit="s")
    check_range("budget_s", budget_s, 0.0, 3600.0, unit="s")
    pts = operating_points(model)
    share = budget_s / len(pts)
    t_begin = timer()
    out = []
    for k, inputs in enumerate(pts):
        period = 2 * math.pi / inputs.omega
        t_point = t_begin + k * share
        st = model.initial_state(inputs)
        st = _run(model, st, inputs, settle_revolutions * period, chunk_s, lambda: timer() >= t_point + share / 2)
        settled, t0, c0 = st.t, timer(), cpu_timer()
        st = _run(model, st, inputs, revolutions * period, chunk_s, lambda: timer() >= t_point + share)
        wall, cpu = timer() - t0, cpu_timer() - c0
        out.append(RtfPoint(inputs.omega, inputs.p_delivery, model.config.fluid.atmospheric_pa,
                            st.t - settled, wall, cpu, settled))
    return StartupRtf(tuple(out), float(threshold), model.bearing_name, timer() - t_begin)
