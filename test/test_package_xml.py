"""package.xml against REP 149 (format 3) and the rosdep keys verified for Jazzy (behaviour).

The key list ``test/data/rosdep_keys_jazzy.yaml`` was checked against
ros/rosdistro (``rosdep/python.yaml``, ``jazzy/distribution.yaml``; commit in
the file); no network is used here.  The structure check follows REP 149's
schema (ros-infrastructure/rep ``xsd/package_format3.xsd``): the sequence
name, version, description, maintainer+, license+, url*, author*, any of the
dependency elements, group_depend*, member_of_group*, export?; name pattern
``[a-z](_?[a-z0-9]+)*``; every dependency element holds one key.
Every third-party module the package imports must be covered by a dependency.
"""
from __future__ import annotations

import ast
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
KEYS = yaml.safe_load((ROOT / "test" / "data" / "rosdep_keys_jazzy.yaml").read_text())
DEPENDS = ("buildtool_depend", "buildtool_export_depend", "build_depend", "build_export_depend", "depend",
           "exec_depend", "test_depend", "doc_depend", "conflict", "replace")
ORDER = ("name", "version", "description", "maintainer", "license", "url", "author") + DEPENDS + (
    "group_depend", "member_of_group", "export")
#: top-level module -> the key that provides it (a new third-party import must be added here and
#: to package.xml with a verified key)
MODULE_KEYS = {
    "numpy": "python3-numpy", "scipy": "python3-scipy", "yaml": "python3-yaml",
    "matplotlib": "python3-matplotlib", "numba": "python3-numba",
    "mcap": "mcap-ros2-support", "mcap_ros2": "mcap-ros2-support",
    "rclpy": "rclpy", "rcl_interfaces": "rcl_interfaces", "std_msgs": "std_msgs",
    "sensor_msgs": "sensor_msgs", "geometry_msgs": "geometry_msgs", "diagnostic_msgs": "diagnostic_msgs",
    "rosgraph_msgs": "rosgraph_msgs", "builtin_interfaces": "builtin_interfaces",
    "ament_index_python": "ament_index_python", "launch": "launch", "launch_ros": "launch_ros",
    "rosbags": "python3-rosbags-pip", "pytest": "python3-pytest",
}
#: imported inside try/except, used only if installed (no dependency declared)
OPTIONAL = {"ross"}   # bearing benchmark's comparison with ross-rotordynamics
#: pip-only: no rosdep key in ros/rosdistro (rosdep/python.yaml at the commit of the key list has no
#: dask/distributed rule); requirements.txt installs them; used only by `sweep`, `batch`, `bench sweep`
PIP_ONLY = {"dask", "distributed"}


def _package():
    return ET.parse(ROOT / "package.xml").getroot()


def test_format3_structure_and_identity():
    root = _package()
    assert root.tag == "package" and root.get("format") == "3"
    tags = [el.tag for el in root]
    assert set(tags) <= set(ORDER), set(tags) - set(ORDER)
    ranks = [ORDER.index(t) if t not in DEPENDS else ORDER.index("depend") for t in tags]
    assert ranks == sorted(ranks), f"REP 149 element order: {tags}"
    for one in ("name", "version", "description", "export"):
        assert tags.count(one) == 1, one
    assert tags.count("maintainer") >= 1 and tags.count("license") >= 1
    assert all(m.get("email") and "@" in m.get("email") for m in root.findall("maintainer"))
    name = root.findtext("name")
    assert re.fullmatch(r"[a-z](_?[a-z0-9]+)*", name)
    setup = (ROOT / "setup.py").read_text()
    assert f'PACKAGE = "{name}"' in setup and (ROOT / "resource" / name).exists()
    version = root.findtext("version")
    assert re.fullmatch(r"\d+\.\d+\.\d+", version) and f'version="{version}"' in setup
    assert root.find("export/build_type").text == "ament_python"


def test_every_dependency_resolves_for_jazzy():
    known = set(KEYS["ros_packages_jazzy"]) | set(KEYS["system_keys"])
    deps = [(el.tag, (el.text or "").strip()) for el in _package() if el.tag in DEPENDS]
    assert deps
    unknown = [d for d in deps if d[1] not in known]
    assert not unknown, f"keys not verified for Jazzy (see test/data/rosdep_keys_jazzy.yaml): {unknown}"
    assert len({d for d in deps}) == len(deps), "a dependency is listed twice"


def _third_party_imports(paths) -> set[str]:
    mods = set()
    for path in paths:
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                mods |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                mods.add(node.module.split(".")[0])
    return {m for m in mods if m not in sys.stdlib_module_names and m not in ("gerotor_twin", "__future__")}


def test_every_import_has_a_dependency():
    code = [*(ROOT / "gerotor_twin").rglob("*.py"), *(ROOT / "launch").glob("*.py")]
    tests = list((ROOT / "test").glob("*.py"))
    runtime = _third_party_imports(code) - OPTIONAL - PIP_ONLY
    unmapped = runtime - set(MODULE_KEYS)
    assert not unmapped, f"imports without a known rosdep key: {sorted(unmapped)}"
    deps = {el.tag: set() for el in _package()}
    for el in _package():
        if el.tag in DEPENDS:
            deps[el.tag].add(el.text.strip())
    run_keys = deps.get("exec_depend", set()) | deps.get("depend", set())
    missing = sorted({MODULE_KEYS[m] for m in runtime} - run_keys)
    assert not missing, f"package imports need exec_depend: {missing}"
    test_only = {m for m in _third_party_imports(tests) if m in MODULE_KEYS} - runtime
    missing_test = sorted({MODULE_KEYS[m] for m in test_only} - run_keys - deps.get("test_depend", set()))
    assert not missing_test, f"tests import without test_depend: {missing_test}"
