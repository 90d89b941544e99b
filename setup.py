"""ament_python package set-up for gerotor_twin (also installable with plain pip)."""
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "gerotor_twin"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    # the flat layout stated explicitly: an editable install is then a plain .pth entry for the source
    # tree (no import-hook finder, no "Editable installation" notice in the install log)
    package_dir={"": "."},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/layouts", glob("layouts/*.json") + glob("layouts/*.xml")),
    ],
    package_data={PACKAGE: ["data/*.yaml", "data/*.json", "report/report.js", "report/vendor/uplot/*"]},
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
