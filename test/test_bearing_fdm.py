"""FDM Reynolds bearing (sec. 2.3) — CLOSED-FORM / INDEPENDENT-SOLVER tests.

* The fast solver (DST in y + cyclic tridiagonal in x) must equal a direct
  sparse solve (scipy.sparse.linalg.spsolve) of the same discretisation,
  assembled here independently from the paper's finite-difference list.
* Grid refinement: the static load converges with observed order ~2
  (reference = the next finer grid, Richardson-style; no stored numbers).
* Motion equation (19): the returned velocity makes the clipped force
  balance the load.
* Paper's grid 320 x 40 runs.
(FDM -> Ocvirk as L/D -> 0 is in test_bearing_steady.py and
test_bearing_squeeze.py.)
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from gerotor_twin.bearing import TABLE1, make_bearing

OMEGA = 500 * 2 * math.pi / 60
C = TABLE1.clearance_m


def _sparse_reference(model, e, e_dot, omega):
    """Assemble Eq. (16) with the paper's stencils (interior rows) and spsolve it."""
    g, gr = model.geometry, model.grid
    nx, ny = gr.nx, gr.ny
    m = ny - 2
    r, mu = g.radius_m, g.viscosity_pa_s
    dx = 2 * math.pi * r / nx
    dy = g.length_m / (ny - 1)
    x = dx * np.arange(nx)
    h = C - e[0] * np.cos(x / r) - e[1] * np.sin(x / r)                  # Eq. (15)
    idx = lambda i, j: (i % nx) * m + (j - 1)  # noqa: E731
    rows, cols, vals = [], [], []
    rhs = np.zeros(nx * m)
    for i in range(nx):
        hb = ((h[i] + h[(i + 1) % nx]) / 2) ** 3
        ha = ((h[i] + h[(i - 1) % nx]) / 2) ** 3
        dhdx = (h[(i + 1) % nx] - h[(i - 1) % nx]) / (2 * dx)
        dhdt = -e_dot[0] * math.cos(x[i] / r) - e_dot[1] * math.sin(x[i] / r)
        for j in range(1, ny - 1):
            k = idx(i, j)
            entries = [(idx(i + 1, j), hb / dx ** 2), (idx(i - 1, j), ha / dx ** 2),
                       (k, -(ha + hb) / dx ** 2 - 2 * h[i] ** 3 / dy ** 2)]
            if j + 1 < ny - 1:
                entries.append((idx(i, j + 1), h[i] ** 3 / dy ** 2))
            if j - 1 > 0:
                entries.append((idx(i, j - 1), h[i] ** 3 / dy ** 2))
            for col, val in entries:
                rows.append(k)
                cols.append(col)
                vals.append(val)
            rhs[k] = 6 * mu * omega * r * dhdx + 12 * mu * dhdt                  # Eq. (14)
    a = sp.csr_matrix((vals, (rows, cols)), shape=(nx * m, nx * m))
    return spl.spsolve(a, rhs).reshape(nx, m)


@pytest.mark.parametrize("nx,ny", [(24, 7), (31, 10), (64, 3)])
@pytest.mark.parametrize("eps,omega", [(0.0, OMEGA), (0.5, OMEGA), (0.9, -2 * OMEGA), (0.7, 0.0)])
def test_fast_solver_equals_sparse_direct_solve(nx, ny, eps, omega):
    model = make_bearing("fdm", TABLE1, nx=nx, ny=ny)
    e = eps * C * np.array([math.cos(0.4), math.sin(0.4)])
    e_dot = np.array([2e-3, -1e-3])
    p = model.pressure_field(e, e_dot, omega)
    ref = _sparse_reference(model, e, e_dot, omega)
    assert np.all(p[:, 0] == 0) and np.all(p[:, -1] == 0)
    np.testing.assert_allclose(p[:, 1:-1], ref, rtol=0, atol=1e-10 * np.abs(ref).max())


@pytest.mark.parametrize("eps", [0.5, 0.8])
def test_grid_convergence_order_two(eps):
    """e on a grid line (phi = 0) so the cavitation boundary sits on nodes."""
    forces = []
    for k in range(5):
        model = make_bearing("fdm", TABLE1, nx=32 * 2 ** k, ny=4 * 2 ** k + 1)
        forces.append(model.film_force([eps * C, 0.0], [0.0, 0.0], OMEGA))
    forces = np.array(forces)
    diffs = np.linalg.norm(np.diff(forces, axis=0), axis=1)
    orders = np.log2(diffs[:-1] / diffs[1:])
    print(f"\nFDM static load, eps = {eps}: |F| =", np.round(np.linalg.norm(forces, axis=1), 4),
          "observed orders", np.round(orders, 3))
    assert np.all(np.abs(orders[1:] - 2.0) < 0.1)


def test_velocity_balances_load_paper_grid():
    model = make_bearing("fdm", TABLE1)  # paper's 320 x 40
    assert (model.grid.nx, model.grid.ny) == (320, 40)
    rng = np.random.default_rng(5)
    for k in range(40):
        eps = rng.uniform(0.0, 0.95)
        a = rng.uniform(-math.pi, math.pi)
        e = eps * C * np.array([math.cos(a), math.sin(a)])
        b = rng.uniform(-math.pi, math.pi)
        load = rng.uniform(10.0, 8000.0) * np.array([math.cos(b), math.sin(b)])
        omega = (OMEGA, 0.0, -OMEGA, 4 * OMEGA)[k % 4]
        v = model.velocity(e, load, omega)
        assert np.all(np.isfinite(v))
        np.testing.assert_allclose(model.film_force(e, v, omega), -load,
                                   atol=1e-8 * np.linalg.norm(load))


def test_clipping_only_removes_negative_pressure():
    model = make_bearing("fdm", TABLE1, nx=64, ny=9)
    e, e_dot = np.array([0.5 * C, 0.1 * C]), np.array([1e-3, 0.0])
    p = model.pressure_field(e, e_dot, OMEGA)
    assert p.min() < 0 < p.max()  # a cavitated region exists
    gr = model.grid
    pos = np.maximum(p, 0.0).sum(axis=1) * gr.dx * gr.dy
    ref = -np.array([np.sum(pos * gr.cos_t), np.sum(pos * gr.sin_t)])     # Eqs. (17)-(18)
    np.testing.assert_allclose(model.film_force(e, e_dot, OMEGA), ref, rtol=1e-12)


def test_fdm_load():
    """Closed form: ``fdm_load`` is the FDM's Eq. (19) read the other way: the FDM velocity kernel (its own Newton
    solve) moves the journal at ė under the load ``fdm_load`` gives for ė (1e-9 of the speed), and its ∂ė/∂F is the
    kernel's central difference in the load (1e-5 of |G|, the clipped force piecewise linear in ė)."""
    from gerotor_twin.bearing.reynolds_fd import fd_fields, fdm_load
    model = make_bearing("fdm", TABLE1, nx=80, ny=12)
    c, _l, d, mu, dx, dy, cos_t, sin_t, lam, synth = model.params
    rng = np.random.default_rng(3)
    for _ in range(20):
        eps, a = rng.uniform(0.1, 0.8), rng.uniform(-math.pi, math.pi)
        e = eps * c * np.array([math.cos(a), math.sin(a)])
        e_dot = rng.normal(size=2) * 10.0 ** rng.uniform(-4, -2)
        omega = rng.choice([0.0, 50.0, 300.0])
        fields = fd_fields(e[0], e[1], omega, c, 0.5 * d, mu, dx, cos_t, sin_t, lam, synth)
        got = np.array(fdm_load(*fields, e_dot[0], e_dot[1], cos_t, sin_t, dx * dy))
        v = np.array(model.kernel(e[0], e[1], got[0], got[1], omega, model.params))
        np.testing.assert_allclose(v, e_dot, rtol=0.0, atol=1e-9 * np.linalg.norm(e_dot))
        h = 1e-6 * np.linalg.norm(got[:2])
        fd = np.column_stack([(np.array(model.kernel(e[0], e[1], *(got[:2] + h * u), omega, model.params))
                               - np.array(model.kernel(e[0], e[1], *(got[:2] - h * u), omega, model.params))) / (2 * h)
                              for u in np.eye(2)])
        np.testing.assert_allclose(got[2:].reshape(2, 2), fd, rtol=0.0, atol=1e-5 * np.abs(fd).max())
