"""Which parameter combinations a set of plateaus can determine (linearised, from the Jacobian).

The weighted Jacobian ``J`` [1/ln] (residuals divided by their standard deviation, against
log-factors ``x``) has its columns scaled to unit norm (``z = D x``, so the answer does not
depend on units) and is decomposed ``J D⁻¹ = U S Vᵀ``.  A direction ``v_k`` whose singular
value is below ``rcond`` × the largest is *not identifiable*: the data change by less than
``rcond`` of the best-determined direction along it.  For two parameters the normalised
singular-value ratio is √((1−|ρ|)/(1+|ρ|)) with ρ their correlation, so ``rcond = 0.1``
means |ρ| > 0.98.  Parameters that load on a non-identifiable direction are
grouped and fitted as one *common* log-factor (their ratios held at the prior: "fit the
identifiable combination, keep the others at the prior"); the data determine the
combination ``c·x`` with ``c = D v₀`` of the group's best-determined direction,
normalised to sum 1, so a common factor f on the group gives c·x = ln f.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["analyse", "covariance", "correlation", "combination_label"]


def analyse(jw: np.ndarray, names, rcond: float = 0.1) -> dict:
    """Identifiability of ``names`` from the weighted Jacobian ``jw`` (m × p) [1/ln].

    Returns
    -------
    dict
        ``scale`` (D, column norms), ``singular_ratios``, ``directions`` (columns of V),
        ``kept`` (indices of identifiable directions), ``groups`` (names fitted together),
        ``basis`` (p × r indicator columns of the groups: x = basis @ b), ``combinations``
        (p × r coefficient vectors c), ``correlation`` (p × p
        from the full problem; NaN when singular), ``unseparable`` (pairs with |ρ| > 0.98 or
        a singular problem), ``insensitive`` (parameters the data do not see at all).
    """
    jw = np.asarray(jw, float)
    p = jw.shape[1]
    if p == 0:
        return {"scale": np.zeros(0), "singular_ratios": np.zeros(0), "directions": np.zeros((0, 0)), "kept": [],
                "basis": np.zeros((0, 0)), "groups": [], "combinations": np.zeros((0, 0)),
                "correlation": np.zeros((0, 0)), "unseparable": [], "insensitive": [], "rcond": rcond}
    d = np.linalg.norm(jw, axis=0)
    sensitive = d > 1e-9 * max(d.max(), 1e-300)
    dd = np.where(sensitive, d, 1.0)
    jn = jw / dd
    jn[:, ~sensitive] = 0.0
    _, s, vt = np.linalg.svd(jn, full_matrices=True)
    s = np.concatenate([s, np.zeros(p - s.size)])
    ratios = s / s[0] if s[0] > 0 else np.zeros_like(s)
    kept = [k for k in range(p) if ratios[k] >= rcond]
    v = vt.T
    groups = _groups(v, ratios, rcond, sensitive)
    basis = np.column_stack([np.isin(np.arange(p), g).astype(float) for g in groups]) if groups else np.zeros((p, 0))
    combos = np.column_stack([_group_combination(jn, dd, g) for g in groups]) if groups else np.zeros((p, 0))
    corr = np.full((p, p), np.nan)
    if ratios.size == p and ratios[-1] > 1e-8:
        corr = correlation(np.linalg.inv(jn.T @ jn))
    pairs = []
    for i in range(p):
        for j in range(i + 1, p):
            if sensitive[i] and sensitive[j] and (not np.isfinite(corr[i, j]) or abs(corr[i, j]) > 0.98):
                pairs.append((names[i], names[j]))
    return {"scale": d, "singular_ratios": ratios, "directions": v, "kept": kept, "basis": basis,
            "groups": [[names[i] for i in g] for g in groups],
            "combinations": combos, "correlation": corr, "unseparable": pairs,
            "insensitive": [names[i] for i in range(p) if not sensitive[i]], "rcond": rcond}


def _groups(v: np.ndarray, ratios: np.ndarray, rcond: float, sensitive: np.ndarray) -> list[list[int]]:
    """Sensitive parameters merged when they load (> 0.1) on the same non-identifiable direction."""
    p = v.shape[0]
    parent = list(range(p))

    def root(i):
        while parent[i] != i:
            i = parent[i]
        return i
    for k in range(p):
        if k < ratios.size and ratios[k] >= rcond:
            continue
        load = [i for i in range(p) if sensitive[i] and abs(v[i, k]) > 0.1]
        for i in load[1:]:
            parent[root(i)] = root(load[0])
    out: dict[int, list[int]] = {}
    for i in range(p):
        if sensitive[i]:
            out.setdefault(root(i), []).append(i)
    return sorted(out.values())


def _group_combination(jn: np.ndarray, dd: np.ndarray, group: list[int]) -> np.ndarray:
    """c = D v₀ of the group's own best-determined direction (sum 1): what the data fix of it."""
    c = np.zeros(dd.size)
    _, _, vt = np.linalg.svd(jn[:, group], full_matrices=False)
    c[group] = _combination(dd[group] * vt[0])
    return c


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def _combination(c: np.ndarray) -> np.ndarray:
    s = c.sum()
    return c / s if abs(s) > 0.1 * np.linalg.norm(c) else _unit(c)


def covariance(jb: np.ndarray, residuals: np.ndarray) -> tuple[np.ndarray, float, int]:
    """Covariance of the fitted coordinates from the weighted Jacobian and the residual scatter.

    ``cov = s² (JᵀJ)⁻¹`` with ``s² = max(1, χ²/(m − r))``: residuals are already divided by
    their measurement standard deviation, so ``s² = 1`` is pure measurement noise; a larger
    scatter (model error, unmodelled effects) widens the intervals accordingly.

    Returns
    -------
    (ndarray, float, int)
        Covariance (r × r), s² and the degrees of freedom m − r.
    """
    m, r = jb.shape
    dof = m - r
    chi2 = float(np.sum(residuals ** 2))
    s2 = max(1.0, chi2 / dof) if dof > 0 else math.nan
    return s2 * np.linalg.pinv(jb.T @ jb), s2, dof


def correlation(cov: np.ndarray) -> np.ndarray:
    """Correlation matrix of a covariance (NaN where a variance is zero)."""
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        return cov / np.outer(sd, sd)


def combination_label(c: np.ndarray, names) -> str:
    """``"0.62·ln(tip) + 0.38·ln(lateral)"`` (terms below 1e-3 dropped)."""
    terms = [f"{ci:+.3f}·ln({n})" for ci, n in zip(c, names) if abs(ci) >= 1e-3]
    return " ".join(terms).lstrip("+") or "0"
