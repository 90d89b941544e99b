"""CLI subcommands bearing-steady / bearing-benchmark — behavioural tests, plus
the PAPER comparison of sec. 2.4 (the three methods give similar trajectories;
Method 1 and the mobility method closest, both being short-bearing models).

Closed-form references: the steady result must agree with the Ocvirk closed
form reported next to it (1 % / 1 deg for mobility and Method 1).
"""
from __future__ import annotations

import argparse
import builtins
import json
import math

import numpy as np
import pytest

from gerotor_twin.bearing.benchmark import (BENCH_OMEGA, benchmark_load, compare_with_ross,
                                            run_benchmark)
from gerotor_twin.bearing.cli_commands import add_parser as register
from gerotor_twin.errors import InputError

STEADY_KEYS = {"eccentricity_ratio", "attitude_angle_deg", "closed_form_eccentricity_ratio",
               "closed_form_attitude_angle_deg", "method", "load_n", "rpm"}


def _parser():
    parser = argparse.ArgumentParser(prog="gerotor-twin")
    register(parser.add_subparsers(dest="command"))
    return parser


@pytest.mark.parametrize("method,extra", [("mobility", []), ("short", ["--rpm", "1500"]),
                                          ("fdm", ["--grid", "96x12"])])
def test_bearing_steady_writes_json(tmp_path, capsys, method, extra):
    out = tmp_path / "steady.json"
    args = _parser().parse_args(["bearing-steady", "--method", method, "--load-n", "1000",
                                 "--load-angle-deg", "-60", "--json", str(out), *extra])
    assert args.func(args) == 0
    data = json.loads(out.read_text())
    assert STEADY_KEYS <= set(data)
    assert data["method"] == method and data["load_n"] == 1000.0
    if method != "fdm":
        assert data["eccentricity_ratio"] == pytest.approx(
            data["closed_form_eccentricity_ratio"], rel=0.01)
        assert data["attitude_angle_deg"] == pytest.approx(
            data["closed_form_attitude_angle_deg"], abs=1.0)
    else:  # finite L/D: the full Reynolds film carries less, eps a little larger
        assert 0 < data["eccentricity_ratio"] - data["closed_form_eccentricity_ratio"] < 0.05
    assert "eccentricity ratio" in capsys.readouterr().out


@pytest.mark.parametrize("argv,field", [
    (["--method", "magic", "--load-n", "10"], "method"),
    (["--load-n", "-5"], "load_n"),
    (["--load-n", "ten"], "load_n"),
    (["--load-n", "10", "--rpm", "0"], "rpm"),
    (["--load-n", "10", "--method", "fdm", "--grid", "320by40"], "grid"),
    (["--load-n", "10", "--method", "fdm", "--grid", "4x40"], "grid.nx"),
])
def test_bearing_steady_bad_input(argv, field):
    args = _parser().parse_args(["bearing-steady", *argv])
    with pytest.raises(InputError) as ei:
        args.func(args)
    assert ei.value.field == field


def test_bearing_benchmark_writes_json_and_plot(tmp_path, capsys):
    js, png = tmp_path / "bench.json", tmp_path / "traj.png"
    args = _parser().parse_args(["bearing-benchmark", "--methods", "mobility,short,fdm",
                                 "--grid", "64x9", "--repeats", "1", "--revolutions", "0.25",
                                 "--json", str(js), "--plot", str(png)])
    assert args.func(args) == 0
    data = json.loads(js.read_text())
    assert set(data["methods"]) == {"mobility", "short", "fdm"}
    assert data["methods"]["fdm"]["paper_matlab_s"] == 43560.0
    assert data["methods"]["short"]["n_steps"] == 1200
    assert png.stat().st_size > 10_000
    out = capsys.readouterr().out
    assert "paper [s]" in out and "Method 1" in out


def test_bearing_benchmark_bad_input():
    for argv, field in ((["--methods", "mobility,foo"], "methods"), (["--repeats", "x"], "repeats"),
                        (["--grid", "axb"], "grid")):
        args = _parser().parse_args(["bearing-benchmark", *argv])
        with pytest.raises(InputError) as ei:
            args.func(args)
        assert ei.value.field == field


def test_ross_absent_message(monkeypatch, capsys):
    real_import = builtins.__import__

    def fake_import(name, *a, **k):
        if name.startswith("ross"):
            raise ImportError("No module named 'ross'")
        return real_import(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    assert compare_with_ross((32, 5)) is None
    assert "ross-rotordynamics not installed" in capsys.readouterr().out


def test_benchmark_load_character():
    """A few hundred N to a few kN, direction swinging about -y, 500 rpm period."""
    t = np.linspace(0.0, 2 * math.pi / BENCH_OMEGA, 4001)
    f = benchmark_load(t)
    mag = np.hypot(f[:, 0], f[:, 1])
    ang = np.degrees(np.arctan2(f[:, 1], f[:, 0]))
    assert 500 < mag.min() < 600 and 2700 < mag.max() < 2800
    assert -150 < ang.min() < -140 and -40 < ang.max() < -30
    np.testing.assert_allclose(f[0], f[-1], atol=1e-9)
    assert benchmark_load(0.0).shape == (2,)


def test_paper_sec24_methods_give_similar_trajectories():
    """Paper sec. 2.4: Method 1 and MM similar (both short bearing, pi-film); FDM
    different but close.  Full paper grid 320 x 40, one revolution."""
    res = run_benchmark(repeats=1, revolutions=1.0)
    d = res.max_difference
    print("\nmax |de|/c over one revolution:", {k: round(v, 4) for k, v in d.items()})
    assert d["mobility vs short"] < 0.03
    assert d["short vs fdm"] < 0.05 and d["mobility vs fdm"] < 0.05
    assert d["mobility vs short"] < d["short vs fdm"]
    assert not any(tr.contact for tr in res.trajectories.values())
