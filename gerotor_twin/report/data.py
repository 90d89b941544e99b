"""Load a bench recording and twin logs for a report, with clear errors (no ROS).

Times are seconds relative to one origin ``t0_ns`` (the first bench message's
log time) so bench and twin series share one axis: the twin's log time is
the clock time of each prediction, which under replay or ``run-bag`` is the
bench's time base.

Required topics (anything else is optional and only drops a figure):

* bench: ``/bench/shaft_speed`` (JointState, ``velocity[0]`` [rad/s]),
  ``/bench/delivery_pressure`` (FluidPressure [Pa abs]),
  ``/bench/delivery_flow`` (Float64 [m³/s], the measured flow);
* twin: ``/twin/flow_summary`` (Float64MultiArray: revolution-mean delivery,
  theoretical, leakage [m³/s], volumetric efficiency [-]).

A topic is also found under a namespace (``/ns/twin/flow_summary``).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gerotor_twin.io import McapReadError, TruncatedMcapWarning, open_mcap, read_topics
from gerotor_twin.io import messages as m
from gerotor_twin.io.reader import multiarray_series, scalar_series

__all__ = ["BENCH_REQUIRED", "TWIN_REQUIRED", "BenchData", "TwinData", "load_bench", "load_twin", "overlap"]

BENCH_REQUIRED = {"/bench/shaft_speed": m.JOINT_STATE, "/bench/delivery_pressure": m.FLUID_PRESSURE,
                  "/bench/delivery_flow": m.FLOAT64}
BENCH_OPTIONAL = {"/bench/suction_pressure": m.FLUID_PRESSURE, "/bench/oil_temperature": m.TEMPERATURE}
TWIN_REQUIRED = {"/twin/flow_summary": m.FLOAT64_MULTIARRAY}
TWIN_OPTIONAL = {"/twin/delivery_flow": m.FLOAT64, "/twin/eccentricity": m.VECTOR3_STAMPED,
                 "/twin/tooth_gaps": m.FLOAT64_MULTIARRAY, "/twin/chamber_waveform": m.FLOAT64_MULTIARRAY,
                 "/twin/chamber_pressures": m.FLOAT64_MULTIARRAY, "/twin/health": m.FLOAT64_MULTIARRAY}


@dataclass
class BenchData:
    """Bench series [s, SI] relative to ``t0_ns``."""
    path: str
    t0_ns: int
    speed: tuple[np.ndarray, np.ndarray]             #: (t [s], ω [rad/s])
    delivery_pressure: tuple[np.ndarray, np.ndarray]  #: (t [s], p [Pa abs])
    flow: tuple[np.ndarray, np.ndarray]              #: (t [s], measured delivery flow [m³/s])
    suction_pressure: tuple[np.ndarray, np.ndarray] | None = None
    temperature: tuple[np.ndarray, np.ndarray] | None = None
    warnings: list[str] = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    library: str = ""                                #: MCAP header: the writing library

    @property
    def span(self) -> tuple[float, float]:
        t = np.concatenate([self.speed[0], self.delivery_pressure[0], self.flow[0]])
        return float(t.min()), float(t.max())


@dataclass
class TwinData:
    """Twin series [s, SI] relative to the bench's ``t0_ns``."""
    path: str
    label: str
    summary: tuple[np.ndarray, np.ndarray]           #: (t [s], (n, 4) mean, theoretical, leakage, η_v)
    flow: tuple[np.ndarray, np.ndarray] | None = None
    eccentricity: tuple[np.ndarray, np.ndarray] | None = None   #: (t, (n, 2) [m])
    gaps: tuple[np.ndarray, np.ndarray] | None = None            #: (t, (n, N) [m])
    waveforms: tuple[np.ndarray, np.ndarray] | None = None       #: (t, (n, samples, 1+N))
    health: tuple[np.ndarray, np.ndarray] | None = None          #: (t, (n, fields)), twin.health.HEALTH_FIELDS
    pump_config_yaml: str | None = None
    parameters: dict = field(default_factory=dict)
    missing: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    meta: dict = field(default_factory=dict)         #: the log's metadata records
    library: str = ""                                #: MCAP header: the writing library

    @property
    def span(self) -> tuple[float, float]:
        t = self.summary[0]
        return float(t.min()), float(t.max())


def _resolve(types: dict[str, str], topic: str) -> str | None:
    if topic in types:
        return topic
    hits = sorted(t for t in types if t.endswith(topic))
    return hits[0] if hits else None


def _check(path: str, types: dict[str, str], required: dict[str, str], optional: dict[str, str]
           ) -> tuple[dict[str, str], list[str]]:
    """Map wanted topics to topics in the file; error listing every missing/wrong one."""
    found, problems, missing = {}, [], []
    for topic, want in {**required, **optional}.items():
        have = _resolve(types, topic)
        if have is None:
            if topic in required:
                problems.append(f"topic {topic} ({want}) is missing")
            else:
                missing.append(topic)
        elif types[have] != want:
            if topic in required:
                problems.append(f"topic {have} is {types[have]}, expected {want}")
            else:
                missing.append(f"{topic} (is {types[have]}, expected {want})")
        else:
            found[topic] = have
    if problems:
        present = ", ".join(f"{k} ({v})" for k, v in sorted(types.items())) or "(none)"
        raise McapReadError(path, "; ".join(problems) + "; topics present: " + present)
    return found, missing


def _read(path: str | Path, required: dict, optional: dict):
    """Open, check topics, read them; collect truncation warnings as text."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", TruncatedMcapWarning)
        f = open_mcap(path)
        found, missing = _check(str(path), f.topic_types(), required, optional)
        series = read_topics(path, list(found.values()))
    notes = [str(w.message) for w in caught if issubclass(w.category, TruncatedMcapWarning)]
    for text in notes:
        warnings.warn(text, TruncatedMcapWarning, stacklevel=3)
    return f, {k: series[v] for k, v in found.items()}, missing, notes


def _nonempty(path, topic, series):
    if len(series) == 0:
        raise McapReadError(path, f"topic {topic} has no messages")
    return series


def load_bench(path: str | Path) -> BenchData:
    """Read the bench topics of a recording.

    Raises
    ------
    McapReadError
        Missing/empty/corrupt file, a required topic missing, empty or of another type.
    """
    f, s, missing, notes = _read(path, BENCH_REQUIRED, BENCH_OPTIONAL)
    for t in BENCH_REQUIRED:
        _nonempty(f.path, t, s[t])
    t0 = int(min(s[t].log_time_ns[0] for t in BENCH_REQUIRED))
    try:
        speed = scalar_series(s["/bench/shaft_speed"], "velocity[0]", t0_ns=t0)
    except Exception as exc:   # noqa: BLE001 - InputError from the field path
        raise McapReadError(f.path, f"/bench/shaft_speed: {exc}") from None
    opt = {}
    for topic, fld in (("/bench/suction_pressure", "fluid_pressure"), ("/bench/oil_temperature", "temperature")):
        opt[topic] = scalar_series(s[topic], fld, t0_ns=t0) if topic in s and len(s[topic]) else None
    return BenchData(path=str(path), t0_ns=t0, speed=speed,
                     delivery_pressure=scalar_series(s["/bench/delivery_pressure"], "fluid_pressure", t0_ns=t0),
                     flow=scalar_series(s["/bench/delivery_flow"], "data", t0_ns=t0),
                     suction_pressure=opt["/bench/suction_pressure"], temperature=opt["/bench/oil_temperature"],
                     warnings=notes, meta=dict(f.metadata), library=f.library or "")


def load_twin(path: str | Path, t0_ns: int, label: str | None = None) -> TwinData:
    """Read the twin topics of a node log or ``run-bag`` output, times relative to ``t0_ns``.

    Raises
    ------
    McapReadError
        As :func:`load_bench`; also a flow summary of the wrong shape.
    """
    f, s, missing, notes = _read(path, TWIN_REQUIRED, TWIN_OPTIONAL)
    _nonempty(f.path, "/twin/flow_summary", s["/twin/flow_summary"])
    try:
        t, v, _ = multiarray_series(s["/twin/flow_summary"], t0_ns=t0_ns)
    except Exception as exc:   # noqa: BLE001
        raise McapReadError(f.path, f"/twin/flow_summary: {exc}") from None
    if v.ndim != 2 or v.shape[1] < 4:
        raise McapReadError(f.path, f"/twin/flow_summary has shape {v.shape[1:]}, expected 4 values "
                                    "(mean, theoretical, leakage [m³/s], volumetric efficiency)")
    meta = f.metadata
    params = meta.get("gerotor_twin.node_parameters", {})
    cfg = meta.get("gerotor_twin.pump_config", {}).get("yaml")
    model = (params.get("bearing_model") or meta.get("gerotor_twin.run_bag", {}).get("model") or "").strip("'\"")
    data = TwinData(path=str(path), label=label or (f"twin ({model})" if model else Path(path).stem),
                    summary=(t, v[:, :4]), pump_config_yaml=cfg, parameters=dict(params),
                    missing=missing, warnings=notes, meta=dict(meta), library=f.library or "")
    for topic, attr in (("/twin/delivery_flow", "flow"), ("/twin/eccentricity", None),
                        ("/twin/tooth_gaps", "gaps"), ("/twin/chamber_waveform", "waveforms"),
                        ("/twin/health", "health")):
        if topic not in s or len(s[topic]) == 0:
            continue
        try:
            if topic == "/twin/delivery_flow":
                data.flow = scalar_series(s[topic], "data", t0_ns=t0_ns)
            elif topic == "/twin/eccentricity":
                te, ex = scalar_series(s[topic], "vector.x", t0_ns=t0_ns)
                _, ey = scalar_series(s[topic], "vector.y", t0_ns=t0_ns)
                data.eccentricity = (te, np.column_stack([ex, ey]))
            else:
                tt, vv, _ = multiarray_series(s[topic], t0_ns=t0_ns)
                setattr(data, attr, (tt, vv))
        except Exception as exc:   # noqa: BLE001 - a malformed optional topic only drops its figure
            data.missing.append(f"{topic} (unreadable: {exc})")
    return data


def pump_config(twin: TwinData):
    """The twin's pump configuration (from the log's metadata, else ``config/pump.yaml``)."""
    from gerotor_twin.config import load_config, parse_config
    from gerotor_twin.yaml_safe import load_yaml
    if twin.pump_config_yaml:
        try:
            raw = load_yaml(twin.pump_config_yaml, f"{twin.path} metadata pump_config")
            return parse_config(raw, source=f"{twin.path} metadata")
        except Exception:   # noqa: BLE001 - fall back to the default pump, noted by the caller
            pass
    return load_config()


def overlap(bench: BenchData, twins: list[TwinData], min_s: float = 1.0) -> tuple[float, float]:
    """Common time span [s] of the bench and every twin file.

    Raises
    ------
    McapReadError
        Naming the twin file whose span does not overlap the bench's by ``min_s``.
    """
    lo, hi = bench.span
    for tw in twins:
        a, b = tw.span
        if min(hi, b) - max(lo, a) < min_s:
            raise McapReadError(tw.path, f"no time overlap with the bench recording {bench.path}: twin "
                                         f"log times {a:.3f}..{b:.3f} s, bench {lo:.3f}..{hi:.3f} s (relative "
                                         f"to {bench.t0_ns} ns); at least {min_s:g} s in common is needed")
        lo, hi = max(lo, a), min(hi, b)
    return lo, hi
