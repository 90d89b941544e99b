"""Which fault kinds a bench's operating points can tell apart on a pump, before a bag is made (no ROS).

``python -m gerotor_twin.offline.diagnosis_bench --separability [--config PUMP]`` prints, for the built-in
``diagnosis`` profile scaled to the pump's range, how well the health monitor's classifier could tell each flow
fault kind from every other: for the true kind a at a loss ``loss`` of the theoretical flow at the monitor's
reference point (θ = ``loss``, a step), the expected log-likelihood ratio Δ(a, b) of a over b
(:func:`~gerotor_twin.twin.diagnosis.separation`) on ``windows`` settled windows per operating point, each with the
monitor's model-error floor as its noise (``rel_sd`` of the flow).  A pair below 2·z² (the classifier's
``separable_z``) is one it names *tentatively* at best on those points (noise alone would reverse the call more
often than Φ(−z)); Δ grows with the number of windows and with the fault's size squared.  The signatures are
those at their finite-difference steps (not re-linearised at the fault's size): a first-order answer.
"""
from __future__ import annotations

from ..twin.diagnosis import FLOW_KINDS, DiagnosisSettings, SteadySignatures, separation
from .model_windows import model_records

__all__ = ["separability", "separability_table", "profile_points"]


def profile_points(cfg) -> list[tuple[float, float]]:
    """The distinct operating points [rpm, bar] of the built-in ``diagnosis`` profile on the pump ``cfg``'s range,
    in the order first visited."""
    from ..bench_emulator import get_profile
    out: list[tuple[float, float]] = []
    for *_, rpm, bar in get_profile("diagnosis", cfg.range).plateaus():
        if (rpm, bar) not in out:
            out.append((rpm, bar))
    return out


def separability(cfg, points, loss: float = 0.04, windows: int = 3, rel_sd: float = 0.003,
                 settings: DiagnosisSettings | None = None) -> dict[str, dict[str, float]]:
    """Δ(a, b) [-] for every pair of flow kinds (module doc) on ``windows`` windows per point of ``points``
    [rpm, bar] at 50 °C oil on the pump ``cfg``, the true kind a at θ = ``loss`` [-], noise ``rel_sd`` of the flow
    [-]; the reference point is the health monitor's, inside the pump's range."""
    from ..twin.health import HealthSettings
    s = settings or DiagnosisSettings()
    hs = HealthSettings().within(cfg.range)
    sig = SteadySignatures(cfg, settings=s, reference=(hs.reference_rpm, hs.reference_bar, hs.reference_oil_c))
    recs = model_records(cfg, {}, 0.0, rel_sd=rel_sd, windows=windows, points=points)
    cols = [sig(r) for r in recs]
    sd = [rel_sd * r.q_pred for r in recs]
    t = [r.t_s for r in recs]
    span = t[-1] - t[0]
    rate_sd = s.prior_sd / span if s.trend and span > 0 else 0.0
    out = {}
    for a in FLOW_KINDS:
        d_a = [c[a] for c in cols]
        fault = [loss * v for v in d_a]
        out[a] = {b: separation(fault, d_a, [c[b] for c in cols], sd, t, s.prior_sd, s.drift_per_sqrt_s, rate_sd)
                  for b in FLOW_KINDS if b != a}
    return out


def separability_table(table: dict[str, dict[str, float]], bound: float) -> str:
    """Markdown: rows the true kind, columns the rival, cells Δ (``**Δ**`` below ``bound``), then the pairs below it."""
    lines = ["| true \\ rival | " + " | ".join(FLOW_KINDS) + " |", "|---" * (len(FLOW_KINDS) + 1) + "|"]
    for a in FLOW_KINDS:
        cells = ["–" if b == a else (f"**{table[a][b]:.1f}**" if table[a][b] < bound else f"{table[a][b]:.1f}")
                 for b in FLOW_KINDS]
        lines.append(f"| {a} | " + " | ".join(cells) + " |")
    pairs = sorted({tuple(sorted((a, b))) for a in table for b in table[a] if table[a][b] < bound})
    lines += ["", f"pairs below {bound:.2f} (named tentatively at best): "
              + (", ".join(f"{a} / {b}" for a, b in pairs) or "none")]
    return "\n".join(lines)
