"""Design-study sweeps (issue 15): SPEC validation, designs, result store, a small sweep, resume.

Tiers: SPEC errors, result store and resume are behaviour tests; the Latin-hypercube
stratification and the grid size are closed form; a sweep point against ``simulate --json``
and against the in-process evaluation is behaviour (same code path, bit-for-bit).  Tests that
start worker processes (embedded LocalCluster) are ``slow``.  Numerics of the tiny studies:
512 table points and 4-degree steps (volumetric efficiency within 2e-4 of the default numerics
at 1500 rpm / 10 bar), at most 8 revolutions.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gerotor_twin.cli import main
from gerotor_twin.errors import InputError
from gerotor_twin.offline.results_store import ResultStore
from gerotor_twin.offline.sweep import run_sweep
from gerotor_twin.offline.sweep_point import evaluate_point
from gerotor_twin.offline.sweep_spec import load_spec, parse_spec

COARSE = {"numerics.table_points": 512, "numerics.max_step_deg": 4.0}
TINY = {
    "title": "tiny", "model": "mobility", "revolutions": 8, "set": COARSE,
    "parameters": {"operating.speed_rpm": [1000, 2500],
                   "gears.lobe_radius_m": [9.0e-3, 18.0e-3]},   # 18 mm > R sin(pi/N) = 17.36 mm: invalid
}
COMPARED = ("id", "index", "params", "status", "reason", "outputs")


def _spec(tmp_path, body: dict, name="spec.yaml"):
    import yaml
    p = tmp_path / name
    p.write_text(yaml.safe_dump(body, sort_keys=False))
    return p


def _records(path) -> list[dict]:
    return [json.loads(x) for x in path.read_text().splitlines()]


def _same(recs: list[dict]) -> dict:
    return {r["id"]: {k: r[k] for k in COMPARED} for r in recs}


@pytest.fixture(scope="module")
def reference():
    """The tiny study evaluated in this process, no engine (what every engine must reproduce)."""
    spec = parse_spec(dict(TINY))
    return {p["id"]: evaluate_point(spec.task(), p) for p in spec.points()}


# ------------------------------------------------------------------ SPEC errors
@pytest.mark.parametrize("body, needle", [
    ({"parameters": {"operating.speed_rpm": [500, 4000]}}, "parameters.operating.speed_rpm = 4000 is invalid; "
                                                          "allowed: (0, 3000] rpm"),
    ({"parameters": {"operating.delivery_bar": {"min": 0, "max": 40, "num": 3}}},
     "parameters.operating.delivery_bar = 40"),
    ({"parameters": {"gears.nonsense_m": [1.0]}}, "parameters.gears.nonsense_m = 1.0 is invalid"),
    ({"parameters": {"clearances.lateral_m": [1e-5, 1e-3]}}, "parameters.clearances.lateral_m = 0.001 is invalid; "
                                                             "allowed: [0, 0.0005) m"),
    ({"parameters": {"bearing_model": ["fixed", "magic"]}}, "parameters.bearing_model = 'magic' is invalid"),
    ({"parameters": {"gears.eccentricity_m": {"min": 3e-3, "max": 4e-3}}}, "min/max alone needs design: lhs | sobol"),
    ({"design": "sobol", "samples": 6, "parameters": {"gears.eccentricity_m": {"min": 3e-3, "max": 4e-3}}},
     "samples = 6 is invalid; allowed: a power of 2"),
    ({"parameters": {"fluid.viscosity_pa_s": {"min": 0.05, "max": 0.01, "num": 3}}},
     "parameters.fluid.viscosity_pa_s.max = 0.01 is invalid; allowed: > min = 0.05"),
    ({"outputs": ["efficiency"]}, "outputs = 'efficiency' is invalid; allowed: volumetric_efficiency"),
    ({"revolutions": 0}, "revolutions = 0 is invalid; allowed: an integer in [1, 1000]"),
    ({"operating": {"rpm": 100}}, "operating.rpm = 100 is invalid; allowed: a field of operating: speed_rpm"),
    ({"set": {"numerics.table_points": 100}}, "set.numerics.table_points = 100 is invalid; allowed: integer in"),
    ({"parameterz": {}}, "parameterz = {} is invalid; allowed: one of the keys"),
])
def test_spec_errors_are_one_line_naming_field_value_range(tmp_path, capsys, body, needle):
    """Behaviour: each SPEC mistake is one line (field, value, allowed range), exit 2, nothing written."""
    with pytest.raises(InputError) as ei:
        parse_spec(body)
    assert needle in str(ei.value)
    p = _spec(tmp_path, body)
    assert main(["sweep", str(p), "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and needle in err
    assert not (tmp_path / "r").exists()


def test_oil_temperature_reaches_the_model_or_is_refused():
    """Behaviour: the operating point carries the oil temperature.  Without a temperature input in the
    model it is a SPEC error; with one, hotter (thinner) oil leaks more: lower volumetric efficiency."""
    from gerotor_twin.offline.sweep_point import temperature_keyword
    body = {"model": "fixed", "revolutions": 6, "set": COARSE, "parameters": {"operating.oil_temperature_c": [30, 80]}}
    if temperature_keyword() is None:
        with pytest.raises(InputError, match="operating.oil_temperature_c = 30 is invalid; allowed: unset"):
            parse_spec(body)
        return
    spec = parse_spec(body)
    cold, hot = (evaluate_point(spec.task(), p) for p in spec.points())
    assert cold["status"] == hot["status"] == "ok"
    assert hot["outputs"]["volumetric_efficiency"] < cold["outputs"]["volumetric_efficiency"]


# ------------------------------------------------------------------ designs
def test_grid_is_the_full_factorial_in_a_fixed_order():
    """Closed form: a grid has prod(len) points; ranges with num/step are linspace / arange."""
    spec = parse_spec({"parameters": {"operating.speed_rpm": {"min": 1000, "max": 3000, "step": 1000},
                                      "operating.delivery_bar": {"min": 5.0, "max": 25.0, "num": 5},
                                      "bearing_model": ["fixed", "mobility"]}})
    pts = spec.points()
    assert len(pts) == 3 * 5 * 2
    assert [p["params"]["operating.speed_rpm"] for p in pts[::10]] == [1000, 2000, 3000]
    assert sorted({p["params"]["operating.delivery_bar"] for p in pts}) == [5.0, 10.0, 15.0, 20.0, 25.0]
    assert [p["id"] for p in pts] == [f"p{i:06d}" for i in range(30)]
    assert spec.points() == pts


def test_latin_hypercube_is_stratified_seeded_and_log_uniform_where_asked():
    """Closed form: n LHS samples put exactly one point in each of the n equal-probability bins per axis."""
    body = {"design": "lhs", "samples": 16, "seed": 3,
            "parameters": {"gears.eccentricity_m": {"min": 3.3e-3, "max": 3.7e-3},
                           "clearances.tooth_tip_m": {"min": 1e-5, "max": 1e-4, "log": True},
                           "bearing_model": ["fixed", "mobility"]}}
    pts = parse_spec(body).points()
    assert len(pts) == 32
    assert pts == parse_spec(body).points()
    assert pts != parse_spec({**body, "seed": 4}).points()
    fixed = [p["params"] for p in pts if p["params"]["bearing_model"] == "fixed"]
    e = np.array([q["gears.eccentricity_m"] for q in fixed])
    d = np.array([q["clearances.tooth_tip_m"] for q in fixed])
    assert sorted(np.floor((e - 3.3e-3) / 0.4e-3 * 16).astype(int)) == list(range(16))
    assert sorted(np.floor(np.log(d / 1e-5) / math.log(10) * 16).astype(int)) == list(range(16))


def test_sobol_sample_is_balanced():
    """Closed form: a scrambled Sobol' sample of 2^m points has one point in each of 2^m bins per axis."""
    pts = parse_spec({"design": "sobol", "samples": 8, "seed": 1,
                      "parameters": {"operating.speed_rpm": {"min": 1000.0, "max": 3000.0},
                                     "operating.delivery_bar": {"min": 0.0, "max": 27.5}}}).points()
    s = np.array([p["params"]["operating.speed_rpm"] for p in pts])
    assert sorted(np.floor((s - 1000) / 2000 * 8).astype(int)) == list(range(8))


# ------------------------------------------------------------------ store
def test_store_keeps_one_record_per_id_and_drops_a_cut_last_line(tmp_path):
    """Behaviour: a second record for an id is refused; a line cut by a crash is dropped (recomputed)."""
    p = tmp_path / "points.jsonl"
    with ResultStore(p) as st:
        assert st.add({"id": "a", "v": 1.0}) and st.add({"id": "b", "v": float("nan")})
        assert not st.add({"id": "a", "v": 2.0})
    with open(p, "a") as fh:
        fh.write('{"id": "c", "v"')
    st = ResultStore(p)
    assert set(st.records) == {"a", "b"} and st.records["a"]["v"] == 1.0 and st.records["b"]["v"] is None
    assert st.dropped_tail == len('{"id": "c", "v"')
    st.add({"id": "c", "v": 3.0})
    st.close()
    assert [r["id"] for r in _records(p)] == ["a", "b", "c"]


# ------------------------------------------------------------------ points
def test_a_point_is_what_simulate_gives(tmp_path, reference):
    """Behaviour: a sweep point equals `simulate --json` of the same pump and operating point (same code)."""
    import yaml
    from gerotor_twin.config import default_config_path
    from gerotor_twin.offline.sweep_point import apply_overrides
    raw = yaml.safe_load(default_config_path().read_text())
    cfg = tmp_path / "pump.yaml"
    cfg.write_text(yaml.safe_dump(apply_overrides(raw, {**COARSE, "gears.lobe_radius_m": 9.0e-3})))
    assert main(["simulate", "--rpm", "2500", "--bar", "10", "--revolutions", "8", "--model", "mobility",
                 "--config", str(cfg), "--json", str(tmp_path / "s.json")]) == 0
    sim = json.loads((tmp_path / "s.json").read_text())
    rec = next(r for r in reference.values() if r["params"] == {"operating.speed_rpm": 2500,
                                                                 "gears.lobe_radius_m": 9.0e-3})
    assert rec["status"] == "ok"
    for k in ("volumetric_efficiency", "delivery_flow_ripple", "min_chamber_pressure_pa", "max_chamber_pressure_pa",
              "min_tooth_gap_m", "revolutions"):
        assert rec["outputs"][k] == sim[k], k
    assert rec["outputs"]["mean_eccentricity_x_m"] == sim["mean_eccentricity_m"][0]
    assert 0.0 <= rec["outputs"]["cavitation_share"] <= 1.0


def test_invalid_geometry_is_a_failed_point_with_its_reason(reference):
    """Behaviour: an undercut lobe radius fails its points with the config's own one-line reason."""
    bad = [r for r in reference.values() if r["params"]["gears.lobe_radius_m"] == 18.0e-3]
    assert len(bad) == 2 and all(r["status"] == "failed" for r in bad)
    assert all(r["reason"].startswith("gears.lobe_radius_m = 0.018 is invalid; allowed: (0, 0.0173") for r in bad)
    good = [r for r in reference.values() if r["status"] == "ok"]
    assert len(good) == 2 and good[0]["outputs"]["volumetric_efficiency"] > 0.5


# ------------------------------------------------------------------ sweeps (worker processes)
@pytest.mark.slow
def test_local_sweep_matches_in_process_and_resumes(tmp_path, reference, capsys):
    """Behaviour: the embedded cluster gives the in-process results bit-for-bit; a cut run resumes with
    every point exactly once; an existing study is not overwritten; a changed SPEC is not resumed."""
    spec_path = _spec(tmp_path, TINY)
    out = tmp_path / "r"
    assert main(["sweep", str(spec_path), "-o", str(out), "--workers", "2"]) == 0
    cap = capsys.readouterr()
    assert "ETA" in cap.err and "4 points, 2 ok, 2 failed" in cap.out
    recs = _records(out / "points.jsonl")
    assert _same(recs) == _same(reference.values())
    html = (out / "summary.html").read_text()
    assert 'id="fig-ripple"' in html and "gears.lobe_radius_m = 0.018 is invalid" in html
    assert (out / "results.csv").read_text().count("\n") == 5

    lines = (out / "points.jsonl").read_text().splitlines(keepends=True)     # crash after 1 point + half a line
    (out / "points.jsonl").write_text(lines[0] + lines[1][:20])
    assert main(["sweep", str(spec_path), "-o", str(out), "--workers", "1"]) == 2
    assert "--resume to continue" in capsys.readouterr().err
    assert main(["sweep", str(spec_path), "-o", str(out), "--workers", "1", "--resume", "--quiet"]) == 0
    again = _records(out / "points.jsonl")
    assert sorted(r["id"] for r in again) == sorted(reference)
    assert _same(again) == _same(reference.values())
    assert "1 kept" in capsys.readouterr().out

    changed = _spec(tmp_path, {**TINY, "revolutions": 9}, "changed.yaml")
    assert main(["sweep", str(changed), "-o", str(out), "--resume"]) == 2
    assert "SPEC (or its base config) changed" in capsys.readouterr().err


def test_scheduler_address_errors(tmp_path, capsys):
    """Behaviour: a malformed or unreachable scheduler address is one line, exit 2."""
    p = _spec(tmp_path, TINY)
    assert main(["sweep", str(p), "-o", str(tmp_path / "a"), "--scheduler", "localhost:8786"]) == 2
    assert "--scheduler = 'localhost:8786' is invalid; allowed: a Dask scheduler address" in capsys.readouterr().err
    assert main(["sweep", str(p), "-o", str(tmp_path / "b"), "--workers", "0"]) == 2
    assert "--workers = 0 is invalid; allowed: an integer in [1, 512]" in capsys.readouterr().err
