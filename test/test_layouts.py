"""The shipped Foxglove and PlotJuggler layouts name real topics and fields of the twin (behaviour).

Every plotted path is resolved against a message of the topic's type built
with the project's codec and decoded again: Foxglove message paths
(``/topic.field[i].sub``) field by field; PlotJuggler series names as its ROS
parser builds them (``/topic/field/sub``, arrays ``[i]``, JointState by joint
name ``/topic/<joint>/velocity``; ros/PlotJuggler ParserROS).  The four
flow-summary values are findable by name in both; every chamber of the packaged pump is plotted from
its own named topic, and the flow residual from ``twin/flow_residual``.  setup.py installs both files.
"""
from __future__ import annotations

import ast
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from gerotor_twin.bench_emulator.emulator import SHAFT_JOINT
from gerotor_twin.io import messages as m
from gerotor_twin.io.codec import encode
from gerotor_twin.twin import INPUTS, SUMMARY_FIELDS
from gerotor_twin.io.decode import decode
from gerotor_twin.twin.outputs import RESIDUAL_FIELDS, chamber_pressure_topics, output_topics, sample_names

ROOT = Path(__file__).resolve().parent.parent
N = 7                                  # chambers of the packaged pump (the layouts plot them all)
TYPES = {"/" + t: mt for t, mt in output_topics(N).items()}
TYPES.update({"/" + s.topic.lstrip("/"): s.msgtype for s in INPUTS.values()})
TYPES["/diagnostics"] = m.DIAGNOSTIC_ARRAY
SAMPLES = {
    m.JOINT_STATE: m.joint_state(1, name=[SHAFT_JOINT], velocity=[1.0]),
    m.FLUID_PRESSURE: m.fluid_pressure(1, 1e5), m.TEMPERATURE: m.temperature(1, 40.0),
    m.FLOAT64: m.float64(1.0), m.VECTOR3_STAMPED: m.vector3_stamped(1, 1.0, 2.0),
    m.DIAGNOSTIC_ARRAY: m.diagnostic_array(1, [m.diagnostic_status(0, "x")]),
}


#: The twin's JointState outputs, with their value names.
NAMED = {"/twin/sample": sample_names(N), "/twin/revolution": SUMMARY_FIELDS, "/twin/flow_residual": RESIDUAL_FIELDS}


def sample(topic: str):
    mt = TYPES[topic]
    if topic in NAMED:
        return decode(mt, encode(mt, m.joint_state(1, name=NAMED[topic], position=np.arange(len(NAMED[topic])) + 0.5)))
    msg = SAMPLES.get(mt) or m.float64_multiarray(np.zeros(7), ("chamber",))
    return decode(mt, encode(mt, msg))


def resolve(obj, steps):
    for name, index in steps:
        obj = getattr(obj, name)
        if index is not None:
            obj = obj[index]
    return obj


def foxglove_path(path: str):
    topic, _, fields = path.partition(".")
    steps = [(mm.group(1), None if mm.group(2) is None else int(mm.group(2)))
             for mm in re.finditer(r"([A-Za-z_]\w*)(?:\[(\d+)\])?", fields)]
    return topic, steps


def test_foxglove_layout():
    lay = json.loads((ROOT / "layouts" / "gerotor_twin.foxglove.json").read_text())
    assert set(lay) >= {"configById", "layout", "globalVariables", "userNodes", "playbackConfig"}

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])
    assert sorted(leaves(lay["layout"])) == sorted(lay["configById"])
    labels = []
    for pid, cfg in lay["configById"].items():
        if pid.startswith("Plot!"):
            for p in cfg["paths"]:
                topic, steps = foxglove_path(p["value"])
                assert topic in TYPES, p["value"]
                value = resolve(sample(topic), steps)
                assert isinstance(value, float), p["value"]
                labels.append(p["label"])
        else:
            assert cfg["topicToRender"] == "/diagnostics"
    for k, name in enumerate(SUMMARY_FIELDS):
        (label,) = [lab for lab in labels if lab.startswith(name)]
        assert (f"/twin/flow_summary.data[{k}]", label) in [
            (p["value"], p["label"]) for c in lay["configById"].values() for p in c.get("paths", ())]
    plotted = {p["value"]: p for c in lay["configById"].values() for p in c.get("paths", ())}
    for topic in chamber_pressure_topics(N):                  # each chamber by name, at its header stamp
        assert plotted[f"/{topic}.fluid_pressure"]["timestampMethod"] == "headerStamp"
    k = RESIDUAL_FIELDS.index("delivery_residual_m3s")
    assert plotted[f"/twin/flow_residual.position[{k}]"]["label"].startswith("delivery_residual_m3s")
    assert plotted[f"/twin/flow_residual.position[{k}]"]["timestampMethod"] == "headerStamp"


def plotjuggler_names(topic: str) -> set[str]:
    """Series names PlotJuggler's ROS parser gives a message of ``topic``."""
    msg = sample(topic)
    if TYPES[topic] == m.JOINT_STATE:
        return {f"{topic}/{j}/{f}" for j in msg.name for f in ("position", "velocity", "effort")}
    out = set()

    def walk(prefix, obj):
        if isinstance(obj, (list, tuple, np.ndarray)):
            for i, v in enumerate(obj):
                walk(f"{prefix}[{i}]", v)
        elif hasattr(obj, "__slots__") or hasattr(obj, "__dict__"):
            names = getattr(obj, "__slots__", None) or list(vars(obj))
            for n in names:
                walk(f"{prefix}/{n.lstrip('_')}", getattr(obj, n.lstrip("_")))
        else:
            out.add(prefix)
    walk(topic, msg)
    return out


def test_plotjuggler_layout():
    root = ET.parse(ROOT / "layouts" / "gerotor_twin.plotjuggler.xml").getroot()
    snippets = {s.get("name"): s for s in root.iter("snippet")}
    assert all(s.findtext("function").strip() == "return value" for s in snippets.values())
    known = set().union(*(plotjuggler_names(t) for t in TYPES))

    def series(name):
        return name in known or (name in snippets and snippets[name].findtext("linked_source") in known)
    curves = [c.get("name") for c in root.iter("curve")]
    assert curves and all(series(c) for c in curves), [c for c in curves if not series(c)]
    for k, name in enumerate(SUMMARY_FIELDS):
        assert snippets[f"flow_summary/{name}"].findtext("linked_source") == f"/twin/flow_summary/data[{k}]"
    assert {f"/{t}/fluid_pressure" for t in chamber_pressure_topics(N)} <= set(curves)
    assert "/twin/flow_residual/delivery_residual_m3s/position" in curves
    assert root.find("tabbed_widget/Tab/Container/DockSplitter") is not None


def test_setup_installs_layouts():
    """Behaviour: both layouts match a pattern of setup.py's ``SHARE`` (the files installed under
    ``share/gerotor_twin/``; that a built wheel holds them is test_install.py's)."""
    tree = ast.parse((ROOT / "setup.py").read_text())
    (share,) = [ast.literal_eval(n.value) for n in tree.body
                if isinstance(n, ast.Assign) and [t.id for t in n.targets] == ["SHARE"]]
    installed = {p for pattern in share for p in ROOT.glob(pattern)}
    layouts = sorted((ROOT / "layouts").iterdir())
    assert len(layouts) == 2 and set(layouts) <= installed
