"""ament_python package set-up for gerotor_twin (also installable with plain pip).

The files the commands read beside the code (the pumps, node parameters, launch file,
layouts, the bundled bench recordings) are installed under ``share/gerotor_twin/`` at
their paths in the source tree, where :mod:`gerotor_twin.resources` finds them.
"""
import os
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "gerotor_twin"

#: files installed under share/gerotor_twin/, at their relative paths in the source tree
SHARE = ("package.xml", "config/*.yaml", "config/pumps/*.yaml", "config/profiles/*.yaml", "config/bench_pumps/*.yaml", "config/maps/*.csv", "config/maps/*.yaml",
         "launch/*.launch.py",
         "layouts/*.json", "layouts/*.xml", "bags/*.mcap", "bags/*.yaml", "bags/README.md")


def share_files(patterns):
    """``data_files`` entries: every file matching ``patterns`` under ``share/<package>/<its directory>``."""
    by_dir = {}
    for pattern in patterns:
        for f in sorted(glob(pattern)):
            by_dir.setdefault(os.path.dirname(f), []).append(f)
    return [(os.path.join("share", PACKAGE, d), files) for d, files in by_dir.items()]


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    # the flat layout stated explicitly: an editable install is then a plain .pth entry for the source
    # tree (no import-hook finder, no "Editable installation" notice in the install log)
    package_dir={"": "."},
    data_files=[("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"])] + share_files(SHARE),
    package_data={PACKAGE: ["report/report.js", "report/vendor/uplot/*"]},
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="gerotor_twin team",
    maintainer_email="gerotor-twin@example.org",
    description="Real-time digital twin of a Gerotor pump (lumped-parameter model with outer-gear micro-motion)",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "gerotor-twin = gerotor_twin.cli:main",
            "twin_node = gerotor_twin.ros.node:main",
        ],
    },
)
