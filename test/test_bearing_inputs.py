"""Bad input — every invalid parameter gives an InputError naming the field
(no reference values; behavioural tests)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from gerotor_twin.bearing import TABLE1, BearingGeometry, make_bearing, settle, simulate, \
    steady_state
from gerotor_twin.bearing import closed_form as cf
from gerotor_twin.bearing.benchmark import compare_with_ross, run_benchmark
from gerotor_twin.errors import InputError

C = TABLE1.clearance_m
OMEGA = 52.36


def _field(exc_info):
    return exc_info.value.field


@pytest.mark.parametrize("kwargs,field", [
    (dict(length_m=0.0), "bearing.length_m"),
    (dict(length_m=-1e-3), "bearing.length_m"),
    (dict(diameter_m=float("nan")), "bearing.diameter_m"),
    (dict(clearance_m=0.0), "bearing.clearance_m"),
    (dict(clearance_m=-1e-5), "bearing.clearance_m"),
    (dict(clearance_m=0.02), "bearing.clearance_m"),
    (dict(viscosity_pa_s=0.0), "bearing.viscosity_pa_s"),
    (dict(viscosity_pa_s=float("inf")), "bearing.viscosity_pa_s"),
    (dict(length_m="abc"), "bearing.length_m"),
])
def test_geometry_validation(kwargs, field):
    base = dict(length_m=17.2e-3, diameter_m=101.55e-3, clearance_m=0.0975e-3,
                viscosity_pa_s=0.0391)
    base.update(kwargs)
    with pytest.raises(InputError) as ei:
        BearingGeometry(**base)
    assert _field(ei) == field
    assert "allowed" in str(ei.value)


def test_table1_values():
    assert TABLE1.length_to_diameter == pytest.approx(17.2 / 101.55)
    assert TABLE1.radius_m == pytest.approx(0.050775)


@pytest.mark.parametrize("name,opts,field", [
    ("hydrostatic", {}, "bearing_model"),
    ("fdm", {"nx": 4}, "grid.nx"),
    ("fdm", {"ny": 2}, "grid.ny"),
    ("fdm", {"nx": 32.5}, "grid.nx"),
    ("short", {"n_nodes": 2}, "n_nodes"),
    ("mobility", {"nx": 10}, "bearing_options"),
])
def test_make_bearing_validation(name, opts, field):
    with pytest.raises(InputError) as ei:
        make_bearing(name, TABLE1, **opts)
    assert _field(ei) == field


def test_make_bearing_geometry_type():
    with pytest.raises(InputError) as ei:
        make_bearing("mobility", {"length_m": 1.0})
    assert _field(ei) == "geometry"


@pytest.mark.parametrize("name", ["fixed", "mobility", "short", "fdm"])
def test_velocity_validation(name):
    m = make_bearing(name, TABLE1, **({"nx": 16, "ny": 5} if name == "fdm" else {}))
    with pytest.raises(InputError) as ei:
        m.velocity([C, 0.0], [0.0, -100.0], OMEGA)          # eps = 1
    assert _field(ei) == "e"
    with pytest.raises(InputError) as ei:
        m.velocity([0.0, 0.0], [float("nan"), 0.0], OMEGA)
    assert _field(ei) == "load"
    with pytest.raises(InputError) as ei:
        m.velocity([0.0, 0.0], [0.0, 1.0, 2.0], OMEGA)
    assert _field(ei) == "load"
    with pytest.raises(InputError) as ei:
        m.velocity([0.0, 0.0], [0.0, 1.0], float("nan"))
    assert _field(ei) == "omega"
    with pytest.raises(InputError) as ei:
        m.film_force([0.0, 0.0], [np.inf, 0.0], OMEGA)
    assert _field(ei) == "e_dot"


@pytest.mark.parametrize("kwargs,field", [
    (dict(e0=[1.2 * C, 0.0]), "e0"),
    (dict(e0=[0.995 * C, 0.0]), "e0"),                 # beyond the contact limit 0.99
    (dict(e0=[0.5 * C, 0.0], eps_max=0.4), "e0"),
    (dict(dt=0.0), "dt"),
    (dict(dt=-1e-4), "dt"),
    (dict(t_end=1e-5), "t_end"),
    (dict(omega=float("nan")), "omega"),
    (dict(eps_max=1.0), "eps_max"),
    (dict(eps_max=0.0), "eps_max"),
    (dict(load_fn=lambda t: [np.nan, 0.0]), "load"),
    (dict(load_fn=[1.0]), "load"),
])
def test_simulate_validation(kwargs, field):
    args = dict(e0=[0.0, 0.0], load_fn=[0.0, -100.0], omega=OMEGA, dt=1e-4, t_end=1e-3)
    args.update(kwargs)
    with pytest.raises(InputError) as ei:
        simulate(make_bearing("mobility", TABLE1), **args)
    assert _field(ei) == field


def test_simulate_model_type():
    with pytest.raises(InputError) as ei:
        simulate("mobility", [0.0, 0.0], [0.0, 1.0], OMEGA, 1e-4, 1e-3)
    assert _field(ei) == "model"


def test_steady_and_settle_validation():
    m = make_bearing("mobility", TABLE1)
    with pytest.raises(InputError) as ei:
        steady_state(m, [0.0, -100.0], 0.0)
    assert _field(ei) == "omega"
    with pytest.raises(InputError) as ei:
        settle(m, [0.0, -100.0], 0.0, [0.0, 0.0])
    assert _field(ei) == "omega"
    with pytest.raises(InputError) as ei:  # needs eps > 0.99: runs into contact
        settle(m, [0.0, -1e6], OMEGA, [0.0, 0.0], t_max=0.1)
    assert _field(ei) == "load"


@pytest.mark.parametrize("call,field", [
    (lambda: cf.ocvirk_load(1.0, TABLE1, OMEGA), "eps"),
    (lambda: cf.ocvirk_attitude_angle(-0.1), "eps"),
    (lambda: cf.ocvirk_eccentricity(-5.0, TABLE1, OMEGA), "load_n"),
    (lambda: cf.ocvirk_eccentricity(100.0, TABLE1, 0.0), "omega"),
    (lambda: cf.squeeze_approach_speed(0.5, -1.0, TABLE1), "load_n"),
    (lambda: cf.squeeze_load_factor(float("nan")), "eps"),
    (lambda: cf.short_bearing_force([C, 0.0], [0.0, 0.0], OMEGA, TABLE1), "eps"),
])
def test_closed_form_validation(call, field):
    with pytest.raises(InputError) as ei:
        call()
    assert _field(ei) == field


@pytest.mark.parametrize("kwargs,field", [
    (dict(methods="mobility,hydrostatic"), "methods"),
    (dict(methods=""), "methods"),
    (dict(repeats=0), "repeats"),
    (dict(revolutions=-1.0), "revolutions"),
    (dict(methods="fdm", grid=(320, 1)), "grid.ny"),
])
def test_benchmark_validation(kwargs, field):
    with pytest.raises(InputError) as ei:
        run_benchmark(**kwargs)
    assert _field(ei) == field


def test_ross_eps_validation():
    with pytest.raises(InputError) as ei:
        compare_with_ross(eps=1.0)
    assert _field(ei) == "eps"


def test_error_message_names_value_and_range():
    with pytest.raises(InputError) as ei:
        BearingGeometry(17.2e-3, 101.55e-3, -1.0, 0.0391)
    msg = str(ei.value)
    assert "bearing.clearance_m" in msg and "-1.0" in msg and "(0, inf) m" in msg
    assert math.isfinite(TABLE1.clearance_ratio)
