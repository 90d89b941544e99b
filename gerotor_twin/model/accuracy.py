"""Accuracy of the default numerics against a tight reference (``gerotor-twin bench accuracy``).

Both runs start from the same state and reach periodic steady state on their
own; one revolution of each is then compared sample by sample (the default
output step is a multiple of the reference's, so the samples coincide in
shaft angle).  Figures, all fractions (not percent):

``pressure_range``
    The reference waveform's range [Pa]: its highest chamber pressure (``peak_pressure``, between
    samples too) minus its lowest sample, over the revolution.  It stays meaningful at a low delivery
    pressure with a large trapped-volume spike, where p_delivery − p_suction does not.
``rms_pressure_error_of_range``
    RMS over samples and chambers of (p − p_ref) / ``pressure_range`` (the budget's figure).
``max_pressure_error_of_range``
    max |p − p_ref| / ``pressure_range``.
``rms_pressure_error``
    RMS over samples and chambers of (p − p_ref) / (p_delivery − p_suction).
``max_pressure_error``
    max |p − p_ref| / (p_delivery − p_suction).
``peak_pressure_error_gauge``
    (p̂ − p̂_ref) / (p̂_ref − p_atm): the peak pressure relative to the reference peak's gauge pressure
    (the budget's figure; equal to ``peak_pressure_error`` where the suction is at atmospheric pressure).
``peak_pressure_error``
    (p̂ − p̂_ref) / (p̂_ref − p_suction): the peak pressure, relative.  p̂ is the highest chamber
    pressure of the revolution as the model reports it (``Outputs.chamber_peak_pressures``: the
    solver's sub-steps and their interpolant, not only the output angles); likewise p̂_ref.
``sampled_peak_error``
    (max p − p̂_ref) / (p̂_ref − p_suction): the peak of the waveform sampled at the output angles;
    the sum of
``peak_numerics_error``
    (max p − max p_ref(θ_test)) / (p̂_ref − p_suction): the solution's error at the peak, both
    taken at the default's own sample angles, and
``peak_sampling_error``
    (max p_ref(θ_test) − p̂_ref) / (p̂_ref − p_suction) ≤ 0: what the coarser output grid
    misses of the reference's peak between its samples (no solver error in it).
``efficiency_error``
    (η − η_ref) / η_ref, volumetric efficiency over the revolution, relative.
``flow_rms_error``
    RMS of (q − q_ref) / mean q_ref, instantaneous delivery flow.
``rtf``
    Real-time factor of the default numerics at this point (simulated / wall time).
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, replace
import numpy as np

from .coupled_reference import coupled_revolution
from .pump import PumpModel
from .steady import reference_config, run_steady
from ..units import bar_gauge_to_pa_abs, rpm_to_rad_s

__all__ = ["accuracy", "compare", "coupled_comparison", "coupled_key_config", "Revolution", "reference_revolution",
           "print_accuracy", "within_budget", "reference_numerics", "reference_check", "BUDGET", "flow_scale_note",
           "SMALL_EFFICIENCY"]

#: The error budget of the default numerics, one for every pump: RMS chamber-pressure error ≤ 1 % of the
#: reference waveform's range, |peak error| ≤ 2 % of the reference peak (gauge), |η error| ≤ 0.3 % relative,
#: delivery-flow RMS ≤ 1 % of the mean flow.
BUDGET = {"rms_pressure_error_of_range": 0.01, "peak_pressure_error_gauge": 0.02, "efficiency_error": 0.003,
          "flow_rms_error": 0.01}


REFERENCE_TOLERANCE = 1e-8   #: sub-step tolerance of the reference, on ln(ρ/ρ₀) [-]
#: reference output steps per default output step (1.5° → 0.094°): 16, where 8 left two references of the family
#: unconverged in their output step (docs/numerics.md, "Accuracy of the defaults")
REFERENCE_REFINEMENT = 16


def reference_numerics(cfg, rpm: float, tolerance: float = REFERENCE_TOLERANCE,
                       refinement: int = REFERENCE_REFINEMENT):
    """The same pump with tight numerics at ``rpm``: an output step ``refinement`` times finer
    than the default's there (so the samples coincide), log-density error control at ``tolerance``."""
    n = cfg.numerics
    h_deg = min(n.max_step_deg, math.degrees(n.max_step_s * rpm_to_rad_s(rpm)))
    steps = math.ceil(360.0 / h_deg - 1e-9)                 # default output steps per revolution
    return reference_config(cfg, tolerance=tolerance, max_step_deg=360.0 / (steps * refinement), max_step_s=1e-2)


def _rtf(model: PumpModel, state, rpm: float, bar: float, revolutions: int) -> tuple[float, float]:
    """(real-time factor, accepted ROS2 sub-steps per revolution) over ``revolutions`` from ``state``."""
    from .pump import Inputs
    inp = Inputs(rpm_to_rad_s(rpm), model.config.boundary.suction_pressure_pa,
                 bar_gauge_to_pa_abs(bar, model.config.fluid.atmospheric_pa))
    span = revolutions * 60.0 / rpm
    t0 = time.perf_counter()
    new, _ = model.advance(state, span, inp)
    wall = time.perf_counter() - t0
    return span / wall, (new.counts["substeps"] - state.counts["substeps"]) / revolutions


@dataclass(frozen=True)
class Revolution:
    """One revolution at periodic steady state, as compared here (SI; angles unwrapped [rad])."""
    theta: np.ndarray               #: (n,) shaft angle of each sample [rad]
    chamber_pressures: np.ndarray   #: (n, N) [Pa]
    delivery_flow: np.ndarray       #: (n,) [m³/s]
    volumetric_efficiency: float    #: [-]
    mean_delivery_flow: float       #: [m³/s]
    peak_pressure: float            #: highest chamber pressure of the revolution, between samples too [Pa]

    @classmethod
    def of(cls, res) -> "Revolution":
        """From a :class:`~gerotor_twin.model.steady.SteadyResult`."""
        o = res.outputs
        return cls(o.theta.copy(), o.chamber_pressures.copy(), o.delivery_flow.copy(), res.volumetric_efficiency,
                   res.mean_delivery_flow_m3s, float(o.chamber_peak_pressures.max()))

    def at(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Chamber pressures and delivery flow at shaft angles θ (another run's samples).

        Chambers turn with the outer gear (period 2πN/(N−1)): k shaft revolutions later
        chamber j sits where chamber j − k was, so the columns are relabelled; between
        samples the reference is interpolated linearly in angle (exact where samples coincide).
        """
        two_pi = 2 * math.pi
        n = self.chamber_pressures.shape[1]
        rev0 = math.floor((self.theta[0] - 1e-9) / two_pi)
        phi_ref = self.theta - two_pi * rev0                       # (0, 2π]
        theta = np.asarray(theta, dtype=float)
        rev = np.floor((theta - 1e-9) / two_pi)
        phi = theta - two_pi * rev
        phi = np.where(phi > phi_ref[-1] + 1e-9, phi - two_pi, phi)     # wrap: below the first sample
        at_phi = np.column_stack([np.interp(phi, phi_ref, self.chamber_pressures[:, c], period=two_pi)
                                  for c in range(n)])               # every reference chamber at each angle
        cols = (np.arange(n)[None, :] - (rev - rev0).astype(np.int64)[:, None]) % n
        p = np.take_along_axis(at_phi, cols, axis=1)
        q = np.interp(phi, phi_ref, self.delivery_flow, period=two_pi)
        return p, q

    def save(self, path, **meta) -> None:
        """Compressed .npz with ``meta`` (numbers/strings) alongside."""
        np.savez_compressed(path, theta=self.theta, chamber_pressures=self.chamber_pressures,
                            delivery_flow=self.delivery_flow,
                            scalars=np.array([self.volumetric_efficiency, self.mean_delivery_flow,
                                              self.peak_pressure]),
                            meta=np.array(json.dumps(meta)))

    @classmethod
    def load(cls, path) -> tuple["Revolution", dict]:
        z = np.load(path)
        if z["scalars"].size != 3:
            raise ValueError(f"{path}: a reference revolution without its peak pressure (written before "
                             "chamber_peak_pressures); regenerate it")
        eta, q, peak = z["scalars"]
        return (cls(z["theta"], z["chamber_pressures"], z["delivery_flow"], float(eta), float(q), float(peak)),
                json.loads(str(z["meta"])))


def compare(test: Revolution, ref: Revolution, p_suction: float, p_delivery: float,
            p_atm: float = 101325.0) -> dict:
    """Error figures of ``test`` against ``ref`` (see the module docstring), fractions [-].

    ``p_suction``, ``p_delivery``, ``p_atm``: the operating point's pressures [Pa, absolute].
    """
    p_ref, q_ref = ref.at(test.theta)
    dp = p_delivery - p_suction
    diff = test.chamber_pressures - p_ref
    err = diff / dp
    peak_ref = ref.peak_pressure
    peak_scale = peak_ref - p_suction
    span = max(peak_ref, float(ref.chamber_pressures.max())) - float(ref.chamber_pressures.min())
    return {
        "pressure_range": span,
        "rms_pressure_error_of_range": float(np.sqrt(np.mean(diff ** 2)) / span),
        "max_pressure_error_of_range": float(np.abs(diff).max() / span),
        "peak_pressure_error_gauge": float((test.peak_pressure - peak_ref) / (peak_ref - p_atm)),
        "rms_pressure_error": float(np.sqrt(np.mean(err ** 2))),
        "max_pressure_error": float(np.abs(err).max()),
        "peak_pressure_error": float((test.peak_pressure - peak_ref) / peak_scale),
        "sampled_peak_error": float((test.chamber_pressures.max() - peak_ref) / peak_scale),
        "peak_numerics_error": float((test.chamber_pressures.max() - p_ref.max()) / peak_scale),
        "peak_sampling_error": float((p_ref.max() - peak_ref) / peak_scale),
        "efficiency_error": float((test.volumetric_efficiency - ref.volumetric_efficiency)
                                  / ref.volumetric_efficiency),
        "flow_rms_error": float(np.sqrt(np.mean((test.delivery_flow - q_ref) ** 2)) / abs(q_ref.mean())),
        "mean_flow_error": float((test.mean_delivery_flow - ref.mean_delivery_flow) / ref.mean_delivery_flow),
        "volumetric_efficiency": test.volumetric_efficiency,
        "reference_volumetric_efficiency": ref.volumetric_efficiency,
    }


def _steady_revolution(ref_cfg, rpm: float, bar: float, model: str, cache=None) -> Revolution:
    """One revolution at periodic steady state of ``ref_cfg`` (its numerics as given), through the
    on-disk cache ``cache`` (a directory; None: computed; :mod:`.reference_cache`)."""
    from .reference_cache import cached_revolution, reference_key
    key = reference_key(ref_cfg, rpm, bar, model) if cache is not None else ""
    rev, _ = cached_revolution(cache, key, lambda: Revolution.of(run_steady(PumpModel(ref_cfg, model), rpm, bar,
                                                                             max_revolutions=40, rtol=1e-6)),
                             Revolution.load)
    return rev


def reference_revolution(cfg, rpm: float, bar: float, model: str = "mobility", cache=None) -> Revolution:
    """The tight reference at one operating point (:func:`reference_numerics`) [rpm, bar gauge].

    ``cache``: a directory of cached references (:mod:`.reference_cache`, keyed by the pump, the point,
    the model and the code); None computes it.
    """
    return _steady_revolution(reference_numerics(cfg, rpm), rpm, bar, model, cache)


def accuracy(cfg, rpm: float = 3000.0, bar: float = 27.5, model: str = "mobility",
             reference: Revolution | None = None, rtf_revolutions: int = 20, coupled: bool = False,
             cache=None) -> dict:
    """Compare the numerics of ``cfg`` with :func:`reference_numerics` at one operating point.

    Parameters
    ----------
    cfg : PumpConfig
        Pump with the numerics under test.
    rpm, bar : float
        Operating point [rpm, bar gauge].
    model : str
        Outer-gear model.
    reference : Revolution, optional
        A precomputed reference revolution (same point), to compare several numerics cheaply.
    coupled : bool
        Also compare with the independent reference of :mod:`.coupled_reference` (mobility only; started from
        the twin's periodic state; minutes per point), as ``row["coupled"]``; ``cache`` as for
        :func:`reference_revolution`.
    """
    ref = reference if reference is not None else reference_revolution(cfg, rpm, bar, model)
    test_model = PumpModel(cfg, model)
    res = run_steady(test_model, rpm, bar, max_revolutions=40, rtol=1e-6)
    ps = cfg.boundary.suction_pressure_pa
    row = {"rpm": rpm, "bar": bar, "model": model,
           "numerics": {k: getattr(cfg.numerics, k) for k in ("max_step_deg", "tolerance", "error_measure",
                                                               "log_density_tolerance", "closing_tolerance")}}
    row.update(compare(Revolution.of(res), ref, ps, bar_gauge_to_pa_abs(bar, cfg.fluid.atmospheric_pa),
                       cfg.fluid.atmospheric_pa))
    if coupled:
        row["coupled"] = coupled_comparison(cfg, rpm, bar, Revolution.of(res), res.state, cache)
    row["rtf"], row["substeps_per_revolution"] = _rtf(test_model, res.state, rpm, bar, rtf_revolutions)
    return row


def coupled_key_config(cfg):
    """The configuration that keys a cached coupled reference: ``cfg`` with the twin's step-control settings at
    their defaults.  The reference reads of the numerics only the tables' resolution (``table_points``) and the
    output step (``max_step_deg``, ``max_step_s``: its sample angles); the rest shapes only the twin's periodic
    state it starts from, which its settling revolution forgets (docs/numerics.md, "The family against the coupled
    reference"), so an A/B of the twin's step control reruns only the twin."""
    from ..config import Numerics
    n = cfg.numerics
    return replace(cfg, numerics=replace(Numerics(), table_points=n.table_points, max_step_deg=n.max_step_deg,
                                         max_step_s=n.max_step_s))


def coupled_comparison(cfg, rpm: float, bar: float, twin: Revolution, state, cache=None) -> dict:
    """The budget figures of the twin's revolution against the coupled reference (:mod:`.coupled_reference`:
    pressures and gear position integrated together by Radau), started from ``state`` [rpm, bar gauge]."""
    from .reference_cache import cached_revolution, reference_key
    key = reference_key(coupled_key_config(cfg), rpm, bar, "mobility-coupled") if cache is not None else ""
    rev, _ = cached_revolution(cache, key, lambda: Revolution(**coupled_revolution(PumpModel(cfg, "mobility"), rpm,
                                                                                     bar, state)[0]), Revolution.load)
    p_atm = cfg.fluid.atmospheric_pa
    err = compare(twin, rev, cfg.boundary.suction_pressure_pa, bar_gauge_to_pa_abs(bar, p_atm), p_atm)
    return {k: err[k] for k in BUDGET} | {"within_budget": within_budget(err)}


def within_budget(row: dict) -> bool:
    """True if a row of :func:`accuracy` meets :data:`BUDGET` (absolute values)."""
    return all(abs(row[k]) <= v for k, v in BUDGET.items())


def reference_check(cfg, rpm: float, bar: float, model: str = "mobility",
                    reference: Revolution | None = None, cache=None) -> dict:
    """How far the reference itself is from a tighter one: each budget figure of :func:`reference_numerics`
    against the same with half its tolerance and twice its output-step refinement, as a fraction of the
    budget (the reference is tight enough where every value is ≤ 0.1).

    ``rpm``, ``bar``: the operating point [rpm, bar gauge].  ``reference``: the reference revolution, if
    already computed.  ``cache``: as for :func:`reference_revolution`.
    """
    ref = reference if reference is not None else reference_revolution(cfg, rpm, bar, model, cache)
    tight = _steady_revolution(reference_numerics(cfg, rpm, REFERENCE_TOLERANCE / 2, 2 * REFERENCE_REFINEMENT),
                               rpm, bar, model, cache)
    p_atm = cfg.fluid.atmospheric_pa
    err = compare(ref, tight, cfg.boundary.suction_pressure_pa, bar_gauge_to_pa_abs(bar, p_atm), p_atm)
    return {k: abs(err[k]) / v for k, v in BUDGET.items()}


#: below this |η| of the reference [-] :func:`print_accuracy` restates the flow figures on the theoretical flow
SMALL_EFFICIENCY = 0.5


def flow_scale_note(row: dict) -> str | None:
    """A line for a point whose reference delivers less than :data:`SMALL_EFFICIENCY` of its theoretical flow
    (low speed, high pressure, worn gaps), else None: the budget's η and flow figures are relative to the mean
    flow, which goes to zero there, so the line restates them on the theoretical flow (the same errors times
    |η_ref|)."""
    eta = row["reference_volumetric_efficiency"]
    if abs(eta) >= SMALL_EFFICIENCY:
        return None
    return (f"    note: the reference delivers η = {eta:.1%} of the theoretical flow, so the η and flow figures above, "
            f"relative to its mean flow, are large by 1/|η|; of the theoretical flow: η "
            f"{100 * row['efficiency_error'] * abs(eta):+.3f} pt, flow RMS {row['flow_rms_error'] * abs(eta):.2%}")


def print_accuracy(cfg, rpms=(3000.0,), bars=(27.5,), models=("mobility",), out=print,
                   check_reference: bool = False, label: str = "", cache=None, coupled: bool = False) -> list[dict]:
    """Run :func:`accuracy` over a grid of points and print one line each, budget verdict included.

    ``check_reference``: also print, per point, how much the reference moves against a tighter one
    (:func:`reference_check`, the largest figure as a fraction of its budget; stored as
    ``reference_check`` in each row).  ``label``: a name printed on the header (a pump of the family).
    ``cache``: a directory of cached references (:mod:`.reference_cache`); None computes each one.
    ``coupled``: also compare the mobility model with the coupled reference (:func:`coupled_comparison`), one
    more line per point.
    """
    n = cfg.numerics
    out(f"{label + ': ' if label else ''}default numerics (output step {n.max_step_deg:g}° / "
        f"{n.max_step_s * 1e6:g} µs, tolerance {n.tolerance:g} on {n.error_measure}) against the reference "
        f"(tolerance {REFERENCE_TOLERANCE:g} on log_density, output step {REFERENCE_REFINEMENT}× finer)")
    out(f"  budget: RMS ≤ {BUDGET['rms_pressure_error_of_range']:.0%} of the reference's pressure range, "
        f"|peak error| ≤ {BUDGET['peak_pressure_error_gauge']:.0%} of its peak (gauge), "
        f"|η error| ≤ {BUDGET['efficiency_error']:.1%} relative, flow RMS ≤ {BUDGET['flow_rms_error']:.0%}")
    out("  peak: of the model's peak output (solver sub-steps); sampled: of the waveform at the output angles,")
    out("  = solver error there + what the output grid misses between them; RMS/Δp: of p_delivery − p_suction")
    out(f"  {'model':9s} {'rpm':>5s} {'bar':>5s} {'range':>7s} {'RMS':>6s} {'max':>6s} {'RMS/Δp':>7s} {'peak':>7s} "
        f"{'sampled':>8s} {'(solver':>8s} {'+ grid)':>8s} {'η err':>8s} {'flow RMS':>8s} {'sub/rev':>7s}"
        f"{'  ref/budget' if check_reference else ''}  verdict")
    rows = []
    for model in models:
        for rpm in rpms:
            for bar in bars:
                ref = reference_revolution(cfg, rpm, bar, model, cache)
                r = accuracy(cfg, rpm, bar, model, reference=ref, coupled=coupled and model == "mobility",
                             cache=cache)
                r["within_budget"] = within_budget(r)
                chk = ""
                if check_reference:
                    r["reference_check"] = reference_check(cfg, rpm, bar, model, reference=ref, cache=cache)
                    chk = f"  {max(r['reference_check'].values()):10.3f}"
                rows.append(r)
                out(f"  {model:9s} {rpm:5.0f} {bar:5.1f} {r['pressure_range'] / 1e5:6.1f}b "
                    f"{r['rms_pressure_error_of_range']:6.2%} {r['max_pressure_error_of_range']:6.1%} "
                    f"{r['rms_pressure_error']:7.2%} {r['peak_pressure_error_gauge']:+7.2%} "
                    f"{r['sampled_peak_error']:+8.2%} {r['peak_numerics_error']:+8.2%} {r['peak_sampling_error']:+8.2%} "
                    f"{r['efficiency_error']:+8.3%} {r['flow_rms_error']:8.2%} {r['substeps_per_revolution']:7.0f}"
                    f"{chk}  {'ok' if r['within_budget'] else 'OUTSIDE BUDGET'}")
                if (note := flow_scale_note(r)) is not None:
                    out(note)
                if "coupled" in r:
                    c = r["coupled"]
                    out(f"    against the coupled reference (pressures and gear position together, Radau): RMS "
                        f"{c['rms_pressure_error_of_range']:.2%}, peak {c['peak_pressure_error_gauge']:+.2%}, "
                        f"η {c['efficiency_error']:+.3%}, flow RMS {c['flow_rms_error']:.2%}  "
                        f"{'ok' if c['within_budget'] else 'OUTSIDE BUDGET'}")
    return rows
