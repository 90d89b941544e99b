"""Bench emulator: synthetic bench recordings for replay, offline runs and reports (no ROS).

================  ==============================================================
module            responsibility
================  ==============================================================
``profiles``      set-point profiles (``map``, ``transient``, ``wear``, ``test``), scaled to
                  the pump's range; checks set-points against it
``profile_file``  a user's profile from YAML (``synth-bench --profile-file``)
``sensors``       :class:`BenchSpec` (what differs from the twin), lags, encoder, oil bath
``bench_pump``    :class:`BenchPump`: a pump and sensors that differ from the twin in form, from
                  YAML (``synth-bench --bench-pump``)
``faults``        :class:`Fault`: fault scenarios (wear, air, suction restriction, sensor faults;
                  ``synth-bench --fault``)
``emulator``      :func:`synthesize`: run the emulated pump, write the MCAP
================  ==============================================================
"""
from gerotor_twin.bench_emulator.bench_pump import BenchPump, load_bench_pump
from gerotor_twin.bench_emulator.emulator import BENCH_TOPICS, EMULATOR_METADATA, synthesize
from gerotor_twin.bench_emulator.faults import FAULT_KINDS, Fault
from gerotor_twin.bench_emulator.profile_file import load_profile_file
from gerotor_twin.bench_emulator.profiles import PROFILES, Profile, Segment, get_profile
from gerotor_twin.bench_emulator.sensors import BenchSpec

__all__ = ["BENCH_TOPICS", "EMULATOR_METADATA", "synthesize", "PROFILES", "Profile", "Segment",
           "get_profile", "load_profile_file", "BenchSpec", "BenchPump", "load_bench_pump", "Fault", "FAULT_KINDS"]
