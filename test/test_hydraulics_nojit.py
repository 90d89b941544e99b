"""The hydraulic kernels on the pure-Python reference path — REGRESSION test.

Runs every kernel of gerotor_twin.hydraulics in a subprocess with
NUMBA_DISABLE_JIT=1 (plain Python ``math``, which raises instead of returning
inf on overflow) over ordinary and degenerate inputs, and checks that the
compiled kernels in this process give the same numbers to round-off.  The
reference here is the code's own uncompiled path, hence "regression".
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

CASES_SRC = r'''
import itertools
FL = (1.5e9, 1000.0, 101325.0, 5000.0, 2000.0)
CASES = []
for p in (-1e9, 0.0, 2000.0, 2000.5, 5e4, 98825.0, 100000.0, 101325.0, 103825.0, 1e7, 1e300):
    CASES.append(("bulk_modulus", (p,) + FL))
    CASES.append(("log_density", (p,) + FL))
    CASES.append(("density_ratio", (p, 3e6) + FL))
    CASES.append(("log_density", (p, 1.5e9, 1e6, 101325.0, 5000.0, 2000.0)))
    CASES.append(("log_density", (p, 1.5e9, 1.0, 101325.0, 5000.0, 2000.0)))
for lam in (0.0, 1.0, 1e3, 1e9):
    CASES.append(("discharge_coefficient", (lam, 0.7, 1000.0)))
for dp, area, mu in itertools.product((0.0, -3.0, 1e5, -1e300), (0.0, 1e-5), (0.0, 0.0391)):
    CASES.append(("orifice_flow", (dp, area, 0.7, 1000.0, 870.0, mu)))
for dp, h in itertools.product((0.0, 1e5, -2e6), (0.0, 2e-5)):
    CASES.append(("slot_flow", (dp, h, 0.017, 1e-3, 0.0391)))
    CASES.append(("tooth_tip_flow", (dp, h, 1e-3, 2.0, 0.017, 0.0391)))
    CASES.append(("tooth_tip_flow", (dp, h, 0.0, 2.0, 0.017, 0.0)))
    CASES.append(("sector_circumferential_flow", (dp, h, 0.4, 0.02, 0.03, 0.0391)))
    CASES.append(("sector_circumferential_flow", (dp, h, 0.0, 0.0, 0.03, 0.0)))
    CASES.append(("sector_radial_flow", (dp, h, 0.4, 0.02, 0.03, 0.0391)))
    CASES.append(("sector_radial_flow", (dp, h, 0.4, 0.03, 0.03, 0.0)))
    CASES.append(("sector_couette_flow", (h, 300.0, 0.02, 0.03)))
'''


def _evaluate(cases):
    import gerotor_twin.hydraulics as H
    out = []
    for name, args in cases:
        r = getattr(H, name)(*args)
        out.append(list(r) if isinstance(r, tuple) else [r])
    return out


def test_pure_python_reference_path():
    ns: dict = {}
    exec(CASES_SRC, ns)
    cases = ns["CASES"]
    script = (CASES_SRC + "\nimport json, gerotor_twin.hydraulics as H\n"
              "assert not hasattr(H.orifice_flow, 'py_func'), 'JIT not disabled'\n"
              "out = []\n"
              "for name, args in CASES:\n"
              "    r = getattr(H, name)(*args)\n"
              "    out.append(list(r) if isinstance(r, tuple) else [r])\n"
              "print(json.dumps(out))\n")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", PYTHONPATH=str(REPO))
    res = subprocess.run([sys.executable, "-c", script], env=env, cwd=REPO,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    ref = json.loads(res.stdout.strip().splitlines()[-1])
    got = _evaluate(cases)
    assert len(ref) == len(got)
    for (name, args), r, g in zip(cases, ref, got):
        for rv, gv in zip(r, g):
            assert math.isfinite(rv) and math.isfinite(gv), (name, args)
            assert gv == pytest.approx(rv, rel=1e-12, abs=1e-300), (name, args)
