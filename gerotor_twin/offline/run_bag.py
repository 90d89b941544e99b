"""``gerotor-twin run-bag``: the twin over a recorded bag, no ROS, as fast as the CPU allows.

The bench messages of the bag are fed, in log-time order, to the same
:class:`~gerotor_twin.twin.core.TwinCore` the node uses (receive time = the
message's log time), the core is ticked on the clock of the bag, and
everything the node would log goes to one MCAP file: the input messages as
recorded (raw CDR bytes, log and publish time), the ``twin/*`` outputs
stamped with their prediction time, and ``/diagnostics`` once per second of
bag time.  Because the core's predictions depend only on the samples and
their receive times (zero-order hold on a fixed grid, see
:mod:`gerotor_twin.twin.core`), not on when ticks happen, the node replaying
the same bag under ``use_sim_time`` gives the same predictions.  The lag
policy is off (``max_span_s = inf``): nothing is skipped.
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path
from typing import IO

import yaml

from gerotor_twin.config import load_config
from gerotor_twin.errors import InputError, one_line
from gerotor_twin.io import McapLog, McapReadError, open_mcap
from gerotor_twin.io.mcap_log import twin_log_metadata
from gerotor_twin.model.pump import BEARING_MODELS, PumpModel
from gerotor_twin.twin.core import TwinCore
from gerotor_twin.twin.inputs import INPUTS
from gerotor_twin.twin.outputs import DIAGNOSTICS_TOPIC, log_topics, output_topics
from gerotor_twin.hydraulics.meter import FLOW_METERS
from gerotor_twin.twin.settings import NS, TwinSettings, oil_sensor_tau_arg

__all__ = ["run_bag", "RUN_BAG_METADATA"]

RUN_BAG_METADATA = "gerotor_twin.run_bag"
_TICK_NS = 50_000_000          # tick the core every 50 ms of bag time (results do not depend on it)


def _topic_kinds(types: dict[str, str], path) -> dict[str, str]:
    """Bag topic -> input kind; error if a required input is missing or of another type."""
    kinds, problems = {}, []
    for kind, spec in INPUTS.items():
        name = "/" + spec.topic
        have = types.get(name)
        if have is None:
            if spec.required:
                problems.append(f"topic {name} ({spec.msgtype}) is missing")
            continue
        if have != spec.msgtype:
            problems.append(f"topic {name} is {have}, expected {spec.msgtype}")
            continue
        kinds[name] = kind
    if problems:
        raise McapReadError(path, "; ".join(problems) + "; topics present: "
                            + (", ".join(f"{k} ({v})" for k, v in sorted(types.items())) or "(none)"))
    return kinds


def _require_messages(rows: list, kinds: dict[str, str], path) -> None:
    """Every required input topic holds messages (a topic that is there but empty is a dead sensor)."""
    count = dict.fromkeys(kinds, 0)
    for _, _, ch, _ in rows:
        count[ch.topic] += 1
    empty = [f"topic {t} ({INPUTS[k].msgtype}) is in the bag but holds no messages (dead sensor or "
             "recorder?); the twin needs it" for t, k in kinds.items() if INPUTS[k].required and not count[t]]
    if empty:
        raise McapReadError(path, "; ".join(empty))


def _require_prediction(core: TwinCore, t_last: int, n_in: int, output) -> None:
    """The model ran at least once; else name why (every sample rejected, inputs never together ...)."""
    if core.stats["initialised"]:
        return
    snap = core.snapshot(t_last)
    rejected = ", ".join(f"{k} {r} {n}" for k, v in snap["inputs"].items() for r, n in v["rejected"].items() if n)
    last = next((v["last_error"] for v in snap["inputs"].values() if v["last_error"]), "")
    raise McapReadError(output, f"the twin never started over the {n_in} input messages ({snap['reason']}); "
                                f"rejected: {rejected or 'none'}{'; last error: ' + last if last else ''}. "
                                "The inputs were written to the output, no prediction")


def _refuse_input_as_output(bag, output) -> None:
    """``-o`` must not be the bag itself (resolved paths, symlinks and hard links included): writing
    the output would replace the recording being read."""
    if not isinstance(output, (str, Path)) or not isinstance(bag, (str, Path)):
        return
    out, src = Path(output), Path(bag)
    try:
        same = out.resolve() == src.resolve() or (out.exists() and src.exists() and out.samefile(src))
    except OSError:
        return                                  # unreadable paths: opening them reports it
    if same:
        raise InputError("-o", str(output), "a file other than the input bag",
                         f"it is the input recording {bag}; writing it would replace the recording")


def run_bag(bag, output, *, model: str = "mobility", config_path=None, settings: TwinSettings | None = None,
            overwrite: bool = False, progress: IO[str] | None = sys.stderr, health=None) -> dict:
    """Run the twin core over a bench bag and write the node's topics to ``output``.

    Parameters
    ----------
    bag : path
        Bench recording (MCAP; ``/bench/shaft_speed`` and ``/bench/delivery_pressure`` required).
    output : path or binary stream
        MCAP to create.
    model : {"mobility", "short", "fdm", "fixed"}
        Outer-gear model of the twin.
    config_path : path, optional
        Pump YAML (default ``config/pump.yaml``).
    settings : TwinSettings, optional
        Core settings (default: the node's defaults with ``max_span_s = inf``).
    progress : text stream or None
        Progress bar with ETA (default stderr).
    health : HealthSettings, optional
        Health monitor settings (default: the node's defaults), :mod:`gerotor_twin.twin.health`.

    Returns
    -------
    dict
        Counts of inputs and outputs, simulated and compute time [s], real-time factor.

    Raises
    ------
    McapReadError
        Unreadable bag, a required topic missing, of another type or holding no
        messages; or inputs the twin cannot use (the model never started: every
        sample rejected, ...; the output is written, with the inputs).
    InputError
        Bad model name or settings; ``output`` is the bag itself.
    """
    if model not in BEARING_MODELS:
        raise InputError("--model", model, " | ".join(BEARING_MODELS))
    _refuse_input_as_output(bag, output)
    f = open_mcap(bag)
    kinds = _topic_kinds(f.topic_types(), f.path)
    rows = []
    for ch, msg in f.iter_raw(list(kinds)):
        rows.append((msg.log_time, msg.publish_time, ch, msg))
    _require_messages(rows, kinds, f.path)
    rows.sort(key=lambda r: r[0])
    cfg = load_config(config_path)
    settings = settings or TwinSettings(max_span_s=math.inf)
    core = TwinCore(PumpModel(cfg, model), settings, health=health)
    cfg_text = Path(cfg.source).read_text() if Path(str(cfg.source)).is_file() else yaml.safe_dump(cfg.to_dict())
    params = {"bearing_model": model, "pump_config": str(cfg.source), "source_bag": str(f.path),
              **{k: repr(v) for k, v in settings.as_dict().items()},
              **{f"health_{k}": repr(v) for k, v in core.health.settings.as_dict().items()}}
    log = McapLog(output, overwrite=overwrite, metadata=twin_log_metadata(
        cfg_text, str(cfg.source), params, {RUN_BAG_METADATA: {"model": model, "bag": str(f.path)}}))
    for topic, msgtype, qos in log_topics({name: f.topic_types()[name] for name in kinds},
                                          outputs=output_topics(core.N)):
        log.add_topic(topic, msgtype, qos=qos)
    t_first, t_last = rows[0][0], rows[-1][0]
    wall0, shown = time.monotonic(), 0.0
    n_out = n_in = 0
    next_tick = (t_first // _TICK_NS + 1) * _TICK_NS
    next_diag = (t_first // NS + 1) * NS

    def tick(now: int) -> None:
        nonlocal n_out, next_diag
        res = core.tick(now)
        for out in res.messages:
            log.write("/" + out.topic, out.msg, out.stamp_ns)
            n_out += 1
        if now >= next_diag:
            log.write(DIAGNOSTICS_TOPIC, core.diagnostics(now), now)
            next_diag = (now // NS + 1) * NS
        core.pop_events()

    try:
        tick(t_first)     # pins the core's time origin to the bag, whatever the tick spacing
        for log_ns, pub_ns, ch, msg in rows:
            while log_ns >= next_tick:
                tick(next_tick)
                next_tick += _TICK_NS
            core.add_message(kinds[ch.topic], f.decode(ch, msg), log_ns, sequence=msg.sequence or None)
            log.write_raw(ch.topic, msg.data, log_ns, pub_ns, sequence=msg.sequence)
            n_in += 1
            now_w = time.monotonic()
            if progress is not None and now_w - shown >= 1.0:
                shown = now_w
                frac = (log_ns - t_first) / max(1, t_last - t_first)
                el = now_w - wall0
                eta = el * (1 - frac) / frac if frac > 0 else float("nan")
                bar = "#" * int(30 * frac)
                print(f"\rrun-bag [{bar:30s}] {100 * frac:5.1f} % {(log_ns - t_first) / NS:7.1f} s of bag, "
                      f"{el:5.0f} s elapsed, ETA {eta:5.0f} s ", end="", file=progress, flush=True)
        tick(t_last)
        stats = core.snapshot(t_last)
    finally:
        log.close()
    _require_prediction(core, t_last, n_in, output if isinstance(output, (str, Path)) else "output")
    wall = time.monotonic() - wall0
    if progress is not None:
        print(f"\rrun-bag [{'#' * 30}] 100.0 % done in {wall:.0f} s" + " " * 30, file=progress, flush=True)
    sim = core.stats["simulated_s"]
    return {"inputs": n_in, "outputs": n_out, "simulated_s": sim, "wall_s": wall,
            "real_time_factor": sim / wall if wall > 0 else None, "revolutions": stats["revolutions"],
            "resets": stats["resets"], "rejected": {k: v["rejected"] for k, v in stats["inputs"].items()}}


def cmd_run_bag(args) -> int:
    out = Path(args.output)
    _refuse_input_as_output(args.bag, out)
    if out.exists() and not args.overwrite:
        raise InputError("-o", str(out), "a file that does not exist yet", "pass --overwrite to replace it")
    settings = TwinSettings(max_span_s=math.inf, oil_sensor_tau_s=oil_sensor_tau_arg(args.oil_sensor_tau),
                            flow_meter=args.flow_meter)
    try:
        res = run_bag(args.bag, out, model=args.model, config_path=args.config, overwrite=args.overwrite,
                      settings=settings, progress=None if args.quiet else sys.stderr,
                      health=health_from_args(args.health))
    except McapReadError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2
    print(f"wrote {out}: {res['inputs']} inputs, {res['outputs']} outputs, {res['revolutions']} revolutions, "
          f"{res['simulated_s']:.1f} s simulated in {res['wall_s']:.1f} s (RTF {res['real_time_factor']:.2f})")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("run-bag", help="run the twin over a bench bag offline (no ROS), write its MCAP",
                       description="Feed a recorded bench bag to the twin core as fast as the CPU allows "
                                   "and write the topics the node would (inputs, twin/*, /diagnostics).")
    p.add_argument("bag", help="bench recording (MCAP)")
    p.add_argument("-o", "--output", required=True, help="MCAP file to write")
    p.add_argument("--model", default="mobility", help="mobility | short | fdm | fixed (default mobility)")
    p.add_argument("--config", help="pump YAML (default config/pump.yaml)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--oil-sensor-tau", type=float, default=0.0, metavar="S",
                   help="time constant of the bench's oil thermometer [s]: the model runs at the reading "
                        "plus S × its rate of change (as the node's oil_sensor_tau_s; default 0 = off)")
    p.add_argument("--flow-meter", choices=FLOW_METERS, default="delivery",
                   help="where the bench's flow meter reads: at the delivery pressure (default) or at atmospheric "
                        "pressure (a return-line meter: its readings are taken to the delivery pressure's volume "
                        "before the residual and the health monitor compare them)")
    p.add_argument("--health", action="append", default=[], metavar="NAME=VALUE",
                   help="health monitor setting, as the node's health_<NAME> parameter (e.g. adapt=true, "
                        "warn_pt=1.5); repeatable")
    p.set_defaults(func=cmd_run_bag)


def health_from_args(items: list[str]):
    """``["adapt=true", "warn_pt=1.5"]`` → :class:`~gerotor_twin.twin.health.HealthSettings` (InputError naming --health)."""
    import dataclasses
    from gerotor_twin.twin.health import HealthSettings
    kinds = {f.name: f.type for f in dataclasses.fields(HealthSettings)}
    kw = {}
    for item in items:
        name, _, text = item.partition("=")
        if name not in kinds or not text:
            raise InputError("--health", item, "NAME=VALUE with NAME one of " + ", ".join(kinds))
        default = getattr(HealthSettings(), name)
        try:
            if isinstance(default, bool):
                if text.lower() not in ("true", "false"):
                    raise ValueError
                kw[name] = text.lower() == "true"
            else:
                kw[name] = type(default)(text)
        except ValueError:
            raise InputError("--health", item, f"{name} as {type(default).__name__}") from None
    return HealthSettings(**kw)
