"""Bench emulator: synthetic bench recordings for replay, offline runs and reports (no ROS).

==============  ==============================================================
module          responsibility
==============  ==============================================================
``profiles``    set-point profiles (``map``, ``transient``, ``test``)
``sensors``     :class:`BenchSpec` (what differs from the twin), lags, encoder
``emulator``    :func:`synthesize`: run the emulated pump, write the MCAP
==============  ==============================================================
"""
from gerotor_twin.bench_emulator.emulator import BENCH_TOPICS, EMULATOR_METADATA, synthesize
from gerotor_twin.bench_emulator.profiles import PROFILES, Profile, Segment, get_profile
from gerotor_twin.bench_emulator.sensors import BenchSpec

__all__ = ["BENCH_TOPICS", "EMULATOR_METADATA", "synthesize", "PROFILES", "Profile", "Segment",
           "get_profile", "BenchSpec"]
