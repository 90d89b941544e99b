"""Which parameter combinations a set of plateaus can determine (linearised, from the Jacobian).

The weighted Jacobian ``J`` [1/ln] (residuals divided by their standard deviation, against
log-factors ``x``) has its columns scaled to unit norm (``z = D x``, so the answer does not
depend on units) and is decomposed ``J D⁻¹ = U S Vᵀ``.  A direction ``v_k`` whose singular
value is below ``rcond`` × the largest is *not identifiable*: the data change by less than
``rcond`` of the best-determined direction along it.  For two parameters the normalised
singular-value ratio is √((1−|ρ|)/(1+|ρ|)) with ρ their correlation, so ``rcond = 0.1``
means |ρ| > 0.98.  The two parameters (or groups) that load most on the weakest direction
are grouped and fitted as one *common* log-factor (their ratios held at the prior: "fit the
identifiable combination, keep the others at the prior"), until the grouped problem has no
direction below ``rcond``; the data determine the
combination ``c·x`` with ``c = D v₀`` of the group's best-determined direction,
normalised to sum 1, so a common factor f on the group gives c·x = ln f.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["analyse", "covariance", "correlation", "combination_label"]


def analyse(jw: np.ndarray, names, rcond: float = 0.1, linear=None) -> dict:
    """Identifiability of ``names`` from the weighted Jacobian ``jw`` (m × p) [1/ln].

    Returns
    -------
    dict
        ``scale`` (D, column norms), ``singular_ratios``, ``directions`` (columns of V),
        ``kept`` (indices of identifiable directions), ``groups`` (names fitted together),
        ``basis`` (p × r indicator columns of the groups: x = basis @ b), ``combinations``
        (p × r coefficient vectors c), ``correlation`` (p × p
        from the full problem; NaN when singular), ``unseparable`` (pairs with |ρ| > 0.98 or
        a singular problem), ``insensitive`` (parameters the data do not see at all), ``fixed`` (parameters
        kept at the prior: confused with two or more others, or fitted linearly and confused with one).

    ``linear`` (p booleans, default none) marks parameters fitted linearly, not as log-factors.
    """
    jw = np.asarray(jw, float)
    p = jw.shape[1]
    if p == 0:
        return {"scale": np.zeros(0), "singular_ratios": np.zeros(0), "directions": np.zeros((0, 0)), "kept": [],
                "basis": np.zeros((0, 0)), "groups": [], "combinations": np.zeros((0, 0)),
                "correlation": np.zeros((0, 0)), "unseparable": [], "insensitive": [], "fixed": [], "rcond": rcond}
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
    groups, fixed = _groups(jw, rcond, sensitive, np.zeros(p, bool) if linear is None else np.asarray(linear, bool))
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
            "insensitive": [names[i] for i in range(p) if not sensitive[i]], "fixed": [names[i] for i in fixed],
            "rcond": rcond}


def _groups(jw: np.ndarray, rcond: float, sensitive: np.ndarray,
            linear: np.ndarray) -> tuple[list[list[int]], list[int]]:
    """Groups of parameters fitted as one common log-factor, and the parameters kept at the prior.

    Greedy: while the grouped problem (a group's column: the sum of its members' columns, the Jacobian of
    their common log-factor) has a singular-value ratio below ``rcond``, the two most nearly parallel
    groups are merged when their own ratio is below ``rcond`` and they act in the same sense (the data see
    them alike: one common factor).  Otherwise one is kept at the prior: of the pair when they act in
    opposite senses (a common factor would cancel), else of all groups (the degeneracy involves three or
    more), the one loading most on the weakest direction — a linearly fitted one (``linear``, which has
    no common factor with another) first.
    """
    groups = [[i] for i in range(jw.shape[1]) if sensitive[i]]
    fixed: list[int] = []
    while len(groups) > 1:
        cols = np.column_stack([jw[:, g].sum(axis=1) for g in groups])
        norms = np.linalg.norm(cols, axis=0)
        _, s, vt = np.linalg.svd(cols / np.where(norms > 0, norms, 1.0), full_matrices=True)
        s = np.concatenate([s, np.zeros(len(groups) - s.size)])
        if s[0] > 0 and s[-1] >= rcond * s[0]:
            break
        cn = cols / np.where(norms > 0, norms, 1.0)
        cos = cn.T @ cn - np.eye(len(groups))
        a, b = np.unravel_index(np.argmax(np.abs(cos)), cos.shape)
        confused = abs(cos[a, b]) > (1 - rcond ** 2) / (1 + rcond ** 2)   # pair ratio √((1−c)/(1+c)) < rcond
        if confused and cos[a, b] > 0 and not linear[groups[a] + groups[b]].any():
            groups[min(a, b)] = sorted(groups[a] + groups[b])
            groups.pop(max(a, b))
        else:
            pair = (a, b) if confused else tuple(range(len(groups)))
            load = [abs(vt[-1][k]) + (1.0 if linear[groups[k]].any() else 0.0) for k in pair]
            fixed += groups.pop(pair[int(np.argmax(load))])
    return sorted(groups), sorted(fixed)


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
