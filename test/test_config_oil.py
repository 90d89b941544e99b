"""The config's ``oil``, ``mixture`` and ``fluid_model`` sections (closed form / behaviour tiers)."""
import math

import pytest
import yaml

from gerotor_twin.config import default_config_path, load_config, parse_config
from gerotor_twin.model.pump import PumpModel

PAPER_OIL = {"density_kg_m3": 870.0, "viscosity_pa_s": 0.0391, "bulk_modulus_pa": 1.5e9}


def raw():
    return yaml.safe_load(default_config_path().read_text())


def constant_form():
    """The default pump with the old constant-property ``fluid`` section (no ``oil``)."""
    r = raw()
    r.pop("oil")
    r["fluid"].update(PAPER_OIL)
    return r


def test_default_oil_is_the_papers_oil_at_its_reference_temperature():
    """Closed form: at 40 °C the default oil has the paper's μ, ρ, β (to the 8 digits of the YAML)."""
    c = load_config()
    assert c.oil is not None and c.reference_temperature_k == 313.15
    assert c.fluid.viscosity_pa_s == pytest.approx(0.0391, rel=1e-7)
    assert c.fluid.density_kg_m3 == pytest.approx(870.0, rel=1e-7)
    assert c.fluid.bulk_modulus_pa == 1.5e9
    assert c.fluid_at(None) == c.fluid
    hot = c.fluid_at(343.15)                 # 70 °C: thinner, lighter, softer
    assert hot.viscosity_pa_s < 0.4 * c.fluid.viscosity_pa_s
    assert hot.density_kg_m3 < c.fluid.density_kg_m3
    assert hot.bulk_modulus_pa == pytest.approx(1.5e9 * (1 - 30 * 2.866e-3), rel=1e-14)


def test_constant_form_still_loads_and_ignores_temperature():
    """Behaviour: a config without ``oil`` keeps constant μ, ρ, β at every temperature."""
    c = parse_config(constant_form())
    assert c.oil is None
    assert c.fluid_at(273.15) == c.fluid == c.fluid_at(373.15)
    assert c.fluid.viscosity_pa_s == 0.0391


def test_constant_form_and_oil_at_reference_give_the_same_kernel_and_efficiency():
    """Behaviour: the paper's μ = 0.0391 Pa·s case is the oil config at 40 °C: same kernel constants
    (relative 1e-7, the digits of the YAML) and the same η at 3000 rpm / 27.5 bar (paper fluid model)."""
    from gerotor_twin.model.steady import run_steady
    a = PumpModel(parse_config(constant_form()).with_fluid_model("paper"), "fixed")
    b = PumpModel(load_config().with_fluid_model("paper"), "fixed")
    for f in ("viscosity", "density", "g_lateral", "g_suction_delivery", "g_drain"):
        assert getattr(a.kernel.pc, f) == pytest.approx(getattr(b.kernel.pc, f), rel=1e-7), f
    ea = run_steady(a, 3000, 27.5).volumetric_efficiency
    eb = run_steady(b, 3000, 27.5).volumetric_efficiency
    assert abs(ea - eb) < 1e-5      # 0.001 pt: tables 3–5 are printed to 0.01 pt (measured 2e-6)


def test_round_trip_through_to_dict():
    """Behaviour: to_dict() parses back to the same fluid, oil laws and mixture."""
    c = load_config()
    d = parse_config(c.to_dict())
    assert d.fluid == c.fluid and d.fluid_model == c.fluid_model and d.air == c.air
    for t in (273.15, 313.15, 363.15):
        assert d.oil.viscosity(t) == pytest.approx(c.oil.viscosity(t), rel=1e-12)
    e = parse_config(parse_config(constant_form()).to_dict())
    assert e.oil is None and e.fluid.viscosity_pa_s == 0.0391


def test_grade_and_points_forms():
    """Closed form: ``grade: 46`` is the VG46 preset; two points give a fit through them."""
    r = raw()
    r["oil"] = {"grade": 46, "reference_temperature_c": 50.0}
    c = parse_config(r)
    assert c.oil.name == "ISO VG46" and c.reference_temperature_k == 323.15
    assert c.oil.kinematic_viscosity(313.15) == pytest.approx(46e-6, rel=1e-12)
    r["oil"] = {"viscosity_points": [[40, "32"], [100, 5.4]], "density_15_kg_m3": 870}
    c = parse_config(r)
    assert c.oil.kinematic_viscosity(373.15) == pytest.approx(5.4e-6, rel=1e-12)
    assert c.fluid.density_kg_m3 == pytest.approx(c.oil.density(313.15))


def test_fluid_model_defaults_to_mixture_and_paper_is_selectable():
    """Behaviour: no ``fluid_model`` key means the mixture; ``paper`` selects eq. (23)."""
    r = raw()
    r.pop("fluid_model")
    assert parse_config(r).fluid_model == "mixture"
    r["fluid_model"] = "paper"
    m = PumpModel(parse_config(r), "fixed")
    assert m.kernel.eos.kind == 0 and math.isclose(m.kernel.eos.ratio, 1000.0)
