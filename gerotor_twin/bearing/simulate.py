"""Integrate a bearing model along a load history; steady states.

The journal is massless, so the state is the centre position ``e`` alone and
every model gives ``de/dt = f(e, F_est(t), omega)`` explicitly (after its own
inner force-balance solve).  :func:`simulate` advances that ODE with the
classical fourth-order Runge-Kutta scheme at a fixed step, entirely inside
numba (the load history is sampled once, up front, at the half steps).

Metal contact.  A trajectory is not allowed past the eccentricity ratio
``eps_max`` (default :data:`EPS_CONTACT` = 0.99, i.e. a minimum film of
1 % of the clearance, ~1 um for Table 1, the order of the combined surface
roughness).  A state that would cross it is projected back radially onto
``|e| = eps_max c`` (the journal then slides along that circle while the load
pushes it outwards), the samples are flagged, and each contiguous contact
interval is reported as a :class:`ContactEvent`.  During contact the film
no longer carries the whole load; the remainder is reported as
``contact_force``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numba
import numpy as np

from gerotor_twin.bearing.base import EPS_KERNEL_CAP, BearingModel, KernelBearing, as_vector2
from gerotor_twin.bearing.closed_form import ocvirk_equilibrium
from gerotor_twin.errors import InputError, check_finite, check_range

__all__ = ["simulate", "BearingTrajectory", "ContactEvent", "steady_state", "settle",
           "EPS_CONTACT", "sample_loads", "SettleResult"]

#: Default contact limit on the eccentricity ratio [-].
EPS_CONTACT = 0.99
_MAX_STEPS = 50_000_000


@dataclass(frozen=True)
class ContactEvent:
    """One contiguous interval in which the journal sat on the contact limit.

    Attributes
    ----------
    t_start, t_end : float
        First and last sample time in contact [s].
    n_samples : int
        Number of samples in contact [-].
    eps_limit : float
        Eccentricity ratio at which the state was clamped [-].
    max_contact_force_n : float
        Largest part of the load not carried by the film [N].
    """

    t_start: float
    t_end: float
    n_samples: int
    eps_limit: float
    max_contact_force_n: float

    def __str__(self) -> str:
        return (f"metal contact (eps clamped at {self.eps_limit:g}) from t = {self.t_start:.6g} s "
                f"to {self.t_end:.6g} s ({self.n_samples} samples, "
                f"max contact force {self.max_contact_force_n:.4g} N)")


@dataclass(frozen=True)
class BearingTrajectory:
    """Result of :func:`simulate` (arrays have one row per sample ``t_n = n dt``).

    Attributes
    ----------
    model : str
        Model name.
    omega : float
        Journal speed [rad/s].
    dt : float
        Time step [s].
    eps_max : float
        Contact limit used [-].
    t : numpy.ndarray, shape (n,)
        Time [s].
    e : numpy.ndarray, shape (n, 2)
        Journal-centre displacement [m].
    e_dot : numpy.ndarray, shape (n, 2)
        Journal-centre velocity [m/s] (radial outward part removed in contact).
    load : numpy.ndarray, shape (n, 2)
        External load [N].
    film_force : numpy.ndarray, shape (n, 2)
        Force of the film on the journal [N] (``-load`` out of contact; for
        the fixed model, the reaction of the rigid support).
    min_film_thickness : numpy.ndarray, shape (n,)
        ``c - |e|`` [m].
    events : tuple of ContactEvent
        Contact intervals (empty if none).
    """

    model: str
    omega: float
    dt: float
    eps_max: float
    clearance_m: float
    t: np.ndarray
    e: np.ndarray
    e_dot: np.ndarray
    load: np.ndarray
    film_force: np.ndarray
    min_film_thickness: np.ndarray
    events: tuple

    @property
    def eccentricity_ratio(self) -> np.ndarray:
        """``|e| / c`` [-], shape (n,)."""
        return np.hypot(self.e[:, 0], self.e[:, 1]) / self.clearance_m

    @property
    def contact(self) -> bool:
        """True if the contact limit was reached."""
        return bool(self.events)

    @property
    def contact_force(self) -> np.ndarray:
        """Load not carried by the film [N], ``-(load + film_force)``, shape (n, 2)."""
        return -(self.load + self.film_force)


@numba.njit(cache=False, nogil=True)
def _project(x, y, rmax):
    r = math.sqrt(x * x + y * y)
    if r > rmax:
        s = rmax / r
        return x * s, y * s, True
    return x, y, False


# Not disk-cached: a numba dispatcher passed as an argument defeats the on-disk cache (the
# index keys on the function object, so every process would append a new entry).  The
# driver is small and is compiled once per process and model kernel.
@numba.njit(cache=False, nogil=True)
def _rk4_run(kernel, params, e0x, e0y, loads, omega, dt, n_steps, rmax, e_out, v_out, contact):
    ex = e0x
    ey = e0y
    for n in range(n_steps + 1):
        e_out[n, 0] = ex
        e_out[n, 1] = ey
        f0x = loads[2 * n, 0]
        f0y = loads[2 * n, 1]
        k1x, k1y = kernel(ex, ey, f0x, f0y, omega, params)
        if contact[n]:
            radial = (k1x * ex + k1y * ey) / (ex * ex + ey * ey)
            if radial > 0.0:  # sliding on the contact circle: no outward motion
                k1x -= radial * ex
                k1y -= radial * ey
        v_out[n, 0] = k1x
        v_out[n, 1] = k1y
        if n == n_steps:
            break
        fmx = loads[2 * n + 1, 0]
        fmy = loads[2 * n + 1, 1]
        f1x = loads[2 * n + 2, 0]
        f1y = loads[2 * n + 2, 1]
        sx, sy, _ = _project(ex + 0.5 * dt * k1x, ey + 0.5 * dt * k1y, rmax)
        k2x, k2y = kernel(sx, sy, fmx, fmy, omega, params)
        sx, sy, _ = _project(ex + 0.5 * dt * k2x, ey + 0.5 * dt * k2y, rmax)
        k3x, k3y = kernel(sx, sy, fmx, fmy, omega, params)
        sx, sy, _ = _project(ex + dt * k3x, ey + dt * k3y, rmax)
        k4x, k4y = kernel(sx, sy, f1x, f1y, omega, params)
        ex, ey, hit = _project(ex + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
                               ey + dt / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y), rmax)
        contact[n + 1] = hit


def sample_loads(load_fn: Any, t: np.ndarray) -> np.ndarray:
    """Evaluate a load history at the times ``t`` [s] -> array (len(t), 2) [N].

    ``load_fn`` is a callable ``t -> (2,)`` (called once with the whole time
    array if it accepts arrays and returns shape (len(t), 2) or (2, len(t)),
    else once per time), or a constant 2-vector.
    """
    n = t.size
    if not callable(load_fn):
        out = np.broadcast_to(as_vector2("load", load_fn), (n, 2)).copy()
    else:
        out = None
        if n > 2:
            try:
                arr = np.asarray(load_fn(t), dtype=float)
                if arr.shape == (n, 2):
                    out = arr.copy()
                elif arr.shape == (2, n):
                    out = arr.T.copy()
            except Exception:  # noqa: BLE001 - not vectorised: fall back to scalar calls
                out = None
        if out is None:
            out = np.array([np.asarray(load_fn(float(ti)), dtype=float).reshape(2) for ti in t])
    if not np.all(np.isfinite(out)):
        bad = int(np.argmin(np.all(np.isfinite(out), axis=1)))
        raise InputError("load", out[bad].tolist(), "finite [N]", f"at t = {t[bad]:g} s")
    return np.ascontiguousarray(out)


def _check_model(model: Any) -> KernelBearing:
    if not isinstance(model, KernelBearing):
        raise InputError("model", model, "a bearing model from make_bearing()")
    return model


def simulate(model: BearingModel, e0: Any, load_fn: Callable | Any, omega: float, dt: float,
             t_end: float, eps_max: float = EPS_CONTACT) -> BearingTrajectory:
    """Integrate the journal-centre motion under a load history (RK4, fixed step).

    Parameters
    ----------
    model : BearingModel
        Model from :func:`gerotor_twin.bearing.make_bearing`.
    e0 : array_like, shape (2,)
        Initial displacement [m], ``|e0| < eps_max c``.
    load_fn : callable or array_like
        ``load_fn(t) -> (2,)`` external load on the journal [N] at time
        ``t`` [s] (vectorised callables are used vectorised), or a constant load.
    omega : float
        Journal speed [rad/s] (constant).
    dt : float
        Time step [s], > 0.
    t_end : float
        End time [s], >= dt; the run has ``round(t_end / dt)`` steps.
    eps_max : float, optional
        Contact limit on the eccentricity ratio [-], in (0, 0.9999].

    Returns
    -------
    BearingTrajectory

    Raises
    ------
    InputError
        For any invalid argument (field named), e.g. ``|e0| >= eps_max c``.
    """
    model = _check_model(model)
    c = model.geometry.clearance_m
    eps_max = check_range("eps_max", eps_max, 0.0, EPS_KERNEL_CAP, lo_open=True)
    e0 = as_vector2("e0", e0)
    eps0 = math.hypot(e0[0], e0[1]) / c
    if eps0 >= eps_max:
        raise InputError("e0", e0.tolist(), f"|e0|/c < eps_max = {eps_max:g}",
                         f"initial eccentricity ratio is {eps0:.6g}")
    omega = check_finite("omega", omega)
    dt = check_range("dt", dt, 0.0, None, lo_open=True, unit="s")
    t_end = check_range("t_end", t_end, dt, None, unit="s")
    n_steps = int(round(t_end / dt))
    if n_steps > _MAX_STEPS:
        raise InputError("t_end", t_end, f"<= {_MAX_STEPS * dt:g} s for dt = {dt:g} s")
    t_half = 0.5 * dt * np.arange(2 * n_steps + 1)
    loads = sample_loads(load_fn, t_half)
    e = np.empty((n_steps + 1, 2))
    v = np.empty((n_steps + 1, 2))
    contact = np.zeros(n_steps + 1, dtype=np.bool_)
    _rk4_run(model.kernel, model.params, e0[0], e0[1], loads, omega, dt, n_steps, eps_max * c,
             e, v, contact)
    load = loads[::2].copy()
    film = -load
    for n in np.flatnonzero(contact):
        film[n] = model.film_force(e[n], v[n], omega)
    t = dt * np.arange(n_steps + 1)
    events = _contact_events(t, contact, -(load + film), eps_max)
    return BearingTrajectory(model.name, omega, dt, eps_max, c, t, e, v, load, film,
                             c - np.hypot(e[:, 0], e[:, 1]), events)


def _contact_events(t, contact, contact_force, eps_max) -> tuple:
    events = []
    idx = np.flatnonzero(contact)
    if idx.size == 0:
        return ()
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate(([idx[0]], idx[breaks + 1]))
    ends = np.concatenate((idx[breaks], [idx[-1]]))
    for a, b in zip(starts, ends):
        fmax = float(np.max(np.hypot(contact_force[a:b + 1, 0], contact_force[a:b + 1, 1])))
        events.append(ContactEvent(float(t[a]), float(t[b]), int(b - a + 1), eps_max, fmax))
    return tuple(events)


def steady_state(model: BearingModel, load: Any, omega: float, e0: Any = None,
                 tol: float = 1e-12, max_iter: int = 60) -> np.ndarray:
    """Equilibrium position under a constant load: the zero of ``velocity(e)``.

    Newton's method on ``e`` with a finite-difference Jacobian of the model
    kernel, damped to stay inside the clearance.

    Parameters
    ----------
    model : BearingModel
        Bearing model.
    load : array_like, shape (2,)
        Constant external load [N].
    omega : float
        Journal speed [rad/s], != 0 (no steady state without rotation).
    e0 : array_like, shape (2,), optional
        Start [m]; default the Ocvirk closed-form equilibrium.
    tol : float, optional
        Stop when ``|de/dt| <= tol c |omega|`` [-].
    max_iter : int, optional
        Newton iterations [-].

    Returns
    -------
    numpy.ndarray, shape (2,)
        Equilibrium displacement [m].

    Raises
    ------
    InputError
        Bad input, or no equilibrium found (e.g. the load needs ``eps >= 0.9999``).
    """
    model = _check_model(model)
    f = as_vector2("load", load)
    omega = check_finite("omega", omega)
    c = model.geometry.clearance_m
    if model.name == "fixed":
        return np.zeros(2) if e0 is None else as_vector2("e0", e0)
    if omega == 0.0:
        raise InputError("omega", omega, "!= 0 rad/s", "no steady state without rotation")
    if e0 is None:
        e = ocvirk_equilibrium(f, model.geometry, omega)
        r = math.hypot(e[0], e[1])
        if r > 0.98 * c:
            e *= 0.98 * c / r
    else:
        e = as_vector2("e0", e0).copy()
    rmax = EPS_KERNEL_CAP * c

    def vel(x):
        return np.array(model.kernel(x[0], x[1], f[0], f[1], omega, model.params))

    v = vel(e)
    scale = c * abs(omega)
    h = 1e-7 * c
    for _ in range(max_iter):
        if np.linalg.norm(v) <= tol * scale:
            return e
        jac = np.empty((2, 2))
        for k in range(2):
            d = np.zeros(2)
            d[k] = h
            jac[:, k] = (vel(e + d) - vel(e - d)) / (2.0 * h)
        step = np.linalg.solve(jac, -v)
        lam = 1.0
        while True:
            trial = e + lam * step
            r = math.hypot(trial[0], trial[1])
            if r < rmax:
                v_trial = vel(trial)
                if np.linalg.norm(v_trial) < np.linalg.norm(v) or lam < 1e-6:
                    break
            lam *= 0.5
            if lam < 1e-6:
                raise InputError("load", f.tolist(), "a load the film can carry",
                                 f"no {model.name} equilibrium found below eps = {EPS_KERNEL_CAP}")
        e, v = trial, v_trial
    if np.linalg.norm(v) <= 1e-8 * scale:
        return e
    raise InputError("load", f.tolist(), "a load the film can carry",
                     f"{model.name} steady-state Newton did not converge")


@dataclass(frozen=True)
class SettleResult:
    """Result of :func:`settle`.

    Attributes
    ----------
    e : numpy.ndarray, shape (2,)
        Settled displacement [m] (Newton-polished equilibrium).
    t_settle : float
        Simulated time until ``|de/dt| < tol c |omega|`` [s] (or ``t_max``).
    settled : bool
        True if the settling criterion was met by time marching.
    e_marched : numpy.ndarray, shape (2,)
        Displacement at the end of the time marching [m], before polishing.
    """

    e: np.ndarray
    t_settle: float
    settled: bool
    e_marched: np.ndarray


def settle(model: BearingModel, load: Any, omega: float, e0: Any, dt: float = 1e-4,
           t_max: float = 5.0, tol: float = 1e-3, chunk: float = 0.05) -> SettleResult:
    """Run a constant load from ``e0`` until the centre settles, then polish.

    Integrates with :func:`simulate` in chunks of ``chunk`` seconds until
    ``|de/dt| < tol c |omega|`` (or ``t_max``), then refines the end point
    with :func:`steady_state` (Newton on ``de/dt = 0``).

    Parameters
    ----------
    model : BearingModel
        Bearing model.
    load : array_like, shape (2,)
        Constant load [N].
    omega : float
        Journal speed [rad/s], != 0.
    e0 : array_like, shape (2,)
        Start [m].
    dt : float, optional
        Step [s].
    t_max : float, optional
        Longest simulated time [s].
    tol : float, optional
        Settling criterion on ``|de/dt| / (c |omega|)`` [-].
    chunk : float, optional
        Integration chunk [s].

    Returns
    -------
    SettleResult

    Raises
    ------
    InputError
        Bad input, or the load drives the journal into contact.
    """
    model = _check_model(model)
    f = as_vector2("load", load)
    omega = check_finite("omega", omega)
    if omega == 0.0 and model.name != "fixed":
        raise InputError("omega", omega, "!= 0 rad/s", "no steady state without rotation")
    t_max = check_range("t_max", t_max, dt, None, unit="s")
    chunk = check_range("chunk", chunk, dt, None, unit="s")
    c = model.geometry.clearance_m
    e = as_vector2("e0", e0)
    t_done = 0.0
    settled = False
    while t_done < t_max:
        traj = simulate(model, e, f, omega, dt, chunk)
        if traj.contact:
            raise InputError("load", f.tolist(), "a load the film can carry",
                             str(traj.events[0]))
        t_done += traj.t[-1]
        e = traj.e[-1]
        if np.linalg.norm(traj.e_dot[-1]) < tol * c * abs(omega) or model.name == "fixed":
            settled = True
            break
    e_final = steady_state(model, f, omega, e0=e)
    return SettleResult(e_final, t_done, settled, e)
