"""A pump's steady map as calibration input (`gerotor-twin calibrate --map F.csv`): parsing, bad rows, the fit.

Tiers: unit conversions against closed forms; bad input (one line per bad row naming row, column, value
and allowed range); the shipped example parses; closed form (synthetic truth): a map made by the twin at
known clearances and a known displacement deficit is recovered within its interval.
"""
import dataclasses
import math

import pytest

from gerotor_twin.cli import main
from gerotor_twin.config import load_config
from gerotor_twin.errors import InputError
from gerotor_twin.calibration.pump_map import MapLimits, PumpMapError, read_map
from gerotor_twin.resources import resource_path

P_ATM = 101325.0
#: displacement 20 cm³/rev, 0–3000 rpm, 0–30 bar: round numbers for the closed forms
LIMITS = MapLimits(displacement_m3=20e-6, p_atm_pa=P_ATM, max_speed_rad_s=3000 * math.pi / 30, max_delivery_pa=30e5)


def _write(tmp_path, text, name="m.csv"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_units_closed_form(tmp_path):
    """Closed form: 1500 rpm = 50π rad/s; 10 bar gauge = p_atm + 1e6 Pa; η_v 90 % of 20 cm³ × 25 rev/s
    = 4.5e-4 m³/s; 30 l/min = 5e-4 m³/s; 323.15 K = 50 °C; 2 MPa gauge; a suction column in bar abs."""
    a = read_map(_write(tmp_path, "# comment\nspeed [rpm],p_delivery [bar],T_oil [degC],eta_v [%]\n"
                                  "1500,10,40,90\n\n2000,20.5,60,85\n"), LIMITS)
    assert [r.index for r in a] == [1, 2]
    assert a[0].omega == pytest.approx(50 * math.pi)
    assert a[0].p_delivery_pa == pytest.approx(P_ATM + 1e6)
    assert a[0].flow_m3s == pytest.approx(0.9 * 20e-6 * 25)
    assert a[0].oil_temperature_c == 40 and math.isnan(a[0].p_suction_pa) and math.isnan(a[0].flow_sem_m3s)
    b = read_map(_write(tmp_path, "n [1/min],p_d [MPa],T_oil [K],Q [l/min],p_s [bar abs]\n2000,2,323.15,30,0.9\n"),
                 LIMITS)[0]
    assert b.flow_m3s == pytest.approx(5e-4) and b.oil_temperature_c == pytest.approx(50.0)
    assert b.p_delivery_pa == pytest.approx(P_ATM + 2e6) and b.p_suction_pa == pytest.approx(0.9e5)


def test_us_units_closed_form(tmp_path):
    """Closed form: a US catalogue's units. 4 gpm = 4 × 3.785411784 L/min (the US gallon, 231 in³);
    122 °F = 50 °C and 212 °F = 100 °C ((F − 32)·5/9); 400 psi gauge = p_atm + 400 × 6894.757293168 Pa;
    a suction column at 14.7 psia = 14.7 × 6894.757293168 Pa absolute."""
    a, b = read_map(_write(tmp_path, "speed [rpm],p_delivery [psi],T_oil [degF],Q [gpm],p_suction [psia]\n"
                                     "1200,400,122,4,14.7\n1800,250,212,6,14.7\n"), LIMITS)
    assert a.flow_m3s == pytest.approx(4 * 3.785411784e-3 / 60, rel=1e-12)
    assert a.oil_temperature_c == pytest.approx(50.0) and b.oil_temperature_c == pytest.approx(100.0)
    assert a.p_delivery_pa == pytest.approx(P_ATM + 400 * 6894.757293168)
    assert a.p_suction_pa == pytest.approx(14.7 * 6894.757293168)


def test_semicolons_tabs_and_decimal_commas(tmp_path):
    """Behaviour: a map saved by a spreadsheet where the comma is the decimal sign (cells separated by
    semicolons, or by tabs, numbers with a decimal comma) reads as the same map with commas and points;
    a bad cell there is named as in any map."""
    rows = [("1000", "12.5", "40", "17.25"), ("2000", "5", "60.5", "39")]
    plain = read_map(_write(tmp_path, "speed [rpm],p_delivery [bar],T_oil [degC],Q [l/min]\n"
                            + "".join(",".join(r) + "\n" for r in rows)), LIMITS)
    for sep in (";", "\t"):
        text = sep.join(["speed [rpm]", "p_delivery [bar]", "T_oil [degC]", "Q [l/min]"]) + "\n" + "".join(
            sep.join(c.replace(".", ",") for c in r) + "\n" for r in rows)
        assert read_map(_write(tmp_path, text, "eu.csv"), LIMITS) == [
            dataclasses.replace(r, bag=str(tmp_path / "eu.csv")) for r in plain]
    with pytest.raises(PumpMapError) as exc:
        read_map(_write(tmp_path, "speed [rpm];p_delivery [bar];T_oil [degC];Q [l/min]\n1000;1.234,5;40;17\n"),
                 LIMITS)
    assert "row 1 (line 2): p_delivery [bar] = '1.234,5'" in exc.value.lines[0]


def test_the_limits_are_the_models_input_envelope(tmp_path):
    """Behaviour: a config's map limits are the twin's input envelope, its rated speed and delivery pressure
    + 10 % (the default pump: 3000 rpm and 27.5 bar rated), and an error names them so."""
    lim = MapLimits.from_config(load_config())
    ok = read_map(_write(tmp_path, "speed [rpm],p_delivery [bar],T_oil [degC],eta_v [-]\n3300,30.25,50,0.9\n"), lim)
    assert ok[0].omega == pytest.approx(3300 * math.pi / 30)
    with pytest.raises(PumpMapError) as exc:
        read_map(_write(tmp_path, "speed [rpm],p_delivery [bar],T_oil [degC],eta_v [-]\n"
                                  "3400,5,50,0.9\n1000,31,50,0.9\n"), lim)
    assert "speed [rpm] = '3400' is invalid; allowed: (0, 3300] rpm (the rated 3000 rpm + 10 %)" in exc.value.lines[0]
    assert ("p_delivery [bar] = '31' is invalid; allowed: [0, 30.25] bar (the rated 27.5 bar + 10 %)"
            in exc.value.lines[1])


def test_bad_rows_one_line_each(tmp_path, capsys):
    """Bad input: each bad row is one line naming its row and line, the column, the value and the allowed
    range (in the column's unit); the good rows do not hide them; the CLI prints them and exits 2."""
    text = ("speed [rpm],p_delivery [bar],T_oil [degC],eta_v [-]\n"
            "1000,5,50,0.9\n"
            "4000,5,50,0.9\n"            # row 2: above the config's speed range
            "1000,abc,50,0.9\n"          # row 3: not a number
            "# a comment between rows\n"
            "1000,5,50,1.5\n")           # row 4 (line 6): η_v above 1.1
    p = _write(tmp_path, text)
    with pytest.raises(PumpMapError) as exc:
        read_map(p, LIMITS)
    lines = exc.value.lines
    assert len(lines) == 3
    assert lines[0].startswith("m.csv row 2 (line 3): speed [rpm] = '4000' is invalid; allowed: (0, 3000] rpm")
    assert "row 3 (line 4): p_delivery [bar]" in lines[1] and "a number in [0, 30] bar" in lines[1]
    assert "row 4 (line 6): eta_v [-] = '1.5'" in lines[2] and "(0, 1.1] -" in lines[2]
    out = tmp_path / "fitted.yaml"
    assert main(["calibrate", "--map", str(p), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(e.startswith("error: m.csv row ") for e in err) and not out.exists()


@pytest.mark.parametrize("header, field", [
    ("speed [rpm],p_delivery [bar],eta_v [-]", "a column t_oil"),
    ("speed [rpm],p_delivery [bar],T_oil [degC]", "exactly one of Q"),
    ("speed [rpm],p_delivery [bar],T_oil [degR],eta_v [-]", "degc | °c | k | degf | °f"),
    ("speed,p_delivery [bar],T_oil [degC],eta_v [-]", "the unit in brackets")])
def test_bad_header(tmp_path, header, field):
    """Bad input: a missing column, a unit not listed, a column without a unit are named."""
    with pytest.raises(InputError, match=field.replace("|", r"\|")):
        read_map(_write(tmp_path, header + "\n1000,5,50,0.9\n"), LIMITS)


@pytest.mark.parametrize("name, config, rows", [("example_map.csv", None, 9),
                                                ("hydreco_1919.csv", "hydreco_1919_pump.yaml", 5)])
def test_shipped_maps_parse(name, config, rows):
    """Behaviour: the maps shipped with the package read with their pump's limits; the published one's η_v
    (92 % at 1200 rpm) becomes 0.92 of the 74.23 cm³/rev of its twin (4.53 in³/rev) at 20 rev/s."""
    cfg = load_config(resource_path("config", "maps", config) if config else None)
    recs = read_map(resource_path("config", "maps", name), MapLimits.from_config(cfg))
    assert len(recs) == rows and len({round(r.rpm) for r in recs}) >= 2
    if config:
        assert recs[0].flow_m3s == pytest.approx(0.92 * 4.53 * 16.387064e-6 * 20, rel=1e-4)
