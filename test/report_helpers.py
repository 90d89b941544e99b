"""Small hand-made bench and twin MCAP files with known content, for the report tests."""
import math

import numpy as np

from gerotor_twin.io import McapLog
from gerotor_twin.io import messages as m

T0 = 1_700_000_000_000_000_000
DISP = 22.78e-6
P_ATM = 101325.0


def profile(t):
    """Two plateaus: 1000 rpm / 10 bar for 0-6 s, then a step to 2000 rpm / 20 bar."""
    rpm = np.where(t < 6.0, 1000.0, 2000.0)
    bar = np.where(t < 6.0, 10.0, 20.0)
    return rpm * math.pi / 30, bar * 1e5 + P_ATM


def eta_true(t):
    return np.where(t < 6.0, 0.95, 0.93)


def oil_c(t):
    """Oil temperature of the synthetic bench [°C]: warming linearly, 30 °C + 2 K/s."""
    return 30.0 + 2.0 * t


def write_bench(path, duration=12.0, *, skip=(), types=None, rate=50.0):
    """Bench topics at ``rate`` Hz; ``skip`` leaves topics out, ``types`` overrides a topic's type."""
    types = {"/bench/shaft_speed": m.JOINT_STATE, "/bench/delivery_pressure": m.FLUID_PRESSURE,
             "/bench/delivery_flow": m.FLOAT64, **(types or {})}
    with McapLog(path, overwrite=True) as log:
        for topic, ty in types.items():
            if topic not in skip:
                log.add_topic(topic, ty, qos="sensor")
        t = np.arange(0, duration, 1 / rate)
        w, p = profile(t)
        q = eta_true(t) * DISP * w / (2 * math.pi)
        for k, tk in enumerate(t):
            ns = T0 + int(round(tk * 1e9))
            for topic, ty in types.items():
                if topic in skip:
                    continue
                if ty == m.JOINT_STATE:
                    msg = m.joint_state(ns, name=["s"], velocity=[w[k]])
                elif ty == m.FLUID_PRESSURE:
                    msg = m.fluid_pressure(ns, p[k])
                elif ty == m.TEMPERATURE:
                    msg = m.temperature(ns, oil_c(tk))
                else:
                    msg = m.float64(q[k])
                log.write(topic, msg, ns)
    return path


def write_twin(path, duration=12.0, *, offset_m3s=1e-5, shift_s=0.0, waveforms=True):
    """Twin topics: per-revolution summaries with prediction = truth + ``offset_m3s``."""
    with McapLog(path, overwrite=True, metadata={"gerotor_twin.node_parameters": {"bearing_model": "fixed"}}) as log:
        for topic, ty in (("/twin/flow_summary", m.FLOAT64_MULTIARRAY), ("/twin/eccentricity", m.VECTOR3_STAMPED),
                          ("/twin/tooth_gaps", m.FLOAT64_MULTIARRAY),
                          ("/twin/chamber_waveform", m.FLOAT64_MULTIARRAY)):
            if waveforms or topic != "/twin/chamber_waveform":
                log.add_topic(topic, ty)
        t = 0.0
        while t < duration:
            w, _ = profile(np.array([t]))
            T = 2 * math.pi / w[0]
            t += T
            ns = T0 + int(round((t + shift_s) * 1e9))
            qth = DISP / T
            q = eta_true(np.array([t]))[0] * qth + offset_m3s
            log.write("/twin/flow_summary", m.float64_multiarray([q, qth, qth - q, q / qth], ("summary",)), ns)
            if waveforms:
                ang = np.linspace(0, 2 * math.pi, 72, endpoint=False)
                tab = np.column_stack([ang] + [P_ATM + 1e5 * (1 + np.sin(ang + j)) for j in range(7)])
                log.write("/twin/chamber_waveform", m.float64_multiarray(tab, ("sample", "angle_p")), ns)
        for k in range(int(duration * 50)):
            tk = k / 50
            ns = T0 + int(round((tk + shift_s) * 1e9))
            log.write("/twin/eccentricity", m.vector3_stamped(ns, 20e-6 * math.cos(tk * 30), 20e-6 * math.sin(tk * 30)), ns)
            log.write("/twin/tooth_gaps", m.float64_multiarray(np.full(7, 10e-6), ("gap",)), ns)
    return path
