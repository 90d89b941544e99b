"""Where every number of the report comes from: files, pump configuration, software, model and numerics.

Each function returns rows ``(item, value)`` of plain text for one provenance table; nothing
here fails the report: an item that cannot be told says so.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import hashlib
import json
from pathlib import Path

from gerotor_twin.software import SOFTWARE_METADATA, software_identity

from .context import ReportContext
from .interactive import UPLOT_VERSION

__all__ = ["file_rows", "pump_rows", "software_rows", "model_rows", "provenance"]

#: Top-level keys of a pump YAML that describe where its values come from (calibration output).
PROVENANCE_KEYS = ("provenance", "calibration")


def _utc(ns: int) -> str:
    return _dt.datetime.fromtimestamp(ns / 1e9, _dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3] + " UTC"


def _sha256(path: str) -> str:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        return f"unreadable ({exc.strerror})"
    return h.hexdigest()


def _file(path: str) -> str:
    p = Path(path)
    try:
        st = p.stat()
    except OSError:
        return f"{path} (not found now)"
    mtime = _dt.datetime.fromtimestamp(st.st_mtime, _dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"{p.name}: {st.st_size / 1e6:.2f} MB, modified {mtime}, sha256 {_sha256(path)}"


def file_rows(ctx: ReportContext) -> list[tuple[str, str]]:
    """Bench recording (dates, duration, sample counts, emulator) and each twin log."""
    b = ctx.bench
    rows = [("bench recording", str(Path(b.path).resolve())), ("bench file", _file(b.path)),
            ("bench start (first message)", _utc(b.t0_ns)),
            ("bench duration", f"{b.span[1] - b.span[0]:.1f} s; {len(b.speed[0])} speed, "
                               f"{len(b.delivery_pressure[0])} pressure, {len(b.flow[0])} flow samples")]
    emu = b.meta.get("gerotor_twin.bench_emulator", {})
    if emu.get("synthetic") == "true":
        rows.append(("bench origin", f"SYNTHETIC (bench emulator), seed {emu.get('seed', '?')}: "
                                     f"{emu.get('command', '')}"))
    for i, tw in enumerate(ctx.twins):
        rows += [(f"twin log {i + 1}: {tw.label}", str(Path(tw.path).resolve())),
                 (f"twin file {i + 1}", _file(tw.path)),
                 (f"twin span {i + 1}", f"{tw.span[0]:.2f} … {tw.span[1]:.2f} s on the bench time axis; "
                                        f"{len(tw.summary[0])} revolution summaries")]
        src = tw.parameters.get("source_bag")
        if src:
            rows.append((f"twin {i + 1} made from", src.strip("'\"") + " (run-bag)"))
    return rows


def _calibration_source(yaml_text: str | None) -> str:
    """The YAML's provenance block, else its comment lines that name a calibration."""
    if not yaml_text:
        return "no pump configuration in the twin log: config/pump.yaml assumed"
    from gerotor_twin.yaml_safe import load_yaml
    try:
        raw = load_yaml(yaml_text, "pump configuration")
    except Exception:   # noqa: BLE001 - provenance must not fail the report
        raw = None
    if isinstance(raw, dict):
        for key in PROVENANCE_KEYS:
            if key in raw:
                return f"{key}: " + json.dumps(raw[key], default=str, ensure_ascii=False)
    notes = [ln.strip().lstrip("#").strip() for ln in yaml_text.splitlines() if "calibrat" in ln.lower()]
    return ("from the file's comments: " + " | ".join(notes)) if notes else "not stated in the configuration"


def pump_rows(ctx: ReportContext) -> list[tuple[str, str]]:
    """Pump configuration of each twin: source file, hash, key values and the calibration source."""
    rows = []
    for i, tw in enumerate(ctx.twins):
        src = (tw.meta.get("gerotor_twin.pump_config", {}).get("path")
               or tw.parameters.get("pump_config", "").strip("'\"") or "?")
        text = tw.pump_config_yaml
        digest = hashlib.sha256(text.encode()).hexdigest()[:16] if text else "-"
        rows.append((f"pump config {i + 1}: {tw.label}", f"{src} (sha256 of the logged YAML {digest}…)"))
        rows.append((f"calibration source {i + 1}", _calibration_source(text)))
    c = ctx.config
    rows.append(("pump (config 1)", f"{c.gears.chambers} chambers, displacement "
                                    f"{ctx.displacement_m3 * 1e6:.3f} cm³/rev, "
                                    f"tooth-tip clearance {c.clearances.tooth_tip_m * 1e6:.2f} µm, lateral "
                                    f"{c.clearances.lateral_m * 1e6:.2f} µm{_opening(c)}, housing radial "
                                    f"{c.clearances.housing_radial_m * 1e6:.2f} µm"))
    return rows


def _opening(cfg) -> str:
    """`` opening 2.00 µm/bar`` for a lateral gap that opens with the pressure load, '' for a rigid one."""
    c = cfg.clearances.lateral_opening_m_per_pa
    return f" (opening {c * 1e11:.2f} µm/bar)" if c else ""


def software_rows(ctx: ReportContext) -> list[tuple[str, str]]:
    """The software that wrote each twin log and the one that wrote this report."""
    me = software_identity()
    rows = [("report written by", f"gerotor_twin {me['version']}, git {me['git_revision']}; uPlot {UPLOT_VERSION}"),
            ("report written at", _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"))]
    for i, tw in enumerate(ctx.twins):
        sw = tw.meta.get(SOFTWARE_METADATA)
        text = (f"gerotor_twin {sw.get('version', '?')}, git {sw.get('git_revision', '?')}" if sw
                else "not recorded in the log (written before the software record existed)")
        rows.append((f"twin log {i + 1} written by", f"{text}; MCAP library: {tw.library or '?'}"))
    rows.append(("bench recording written by", ctx.bench.library or "?"))
    return rows


def model_rows(ctx: ReportContext) -> list[tuple[str, str]]:
    """Bearing model, node / run-bag parameters and the pump's numerics block, per twin."""
    rows = []
    for i, tw in enumerate(ctx.twins):
        prm = {k: v.strip("'\"") for k, v in tw.parameters.items()}
        rows.append((f"model {i + 1}: {tw.label}", f"bearing model {prm.get('bearing_model', '?')}"))
        rest = {k: v for k, v in prm.items() if k not in ("bearing_model", "pump_config", "source_bag")}
        if rest:
            rows.append((f"twin parameters {i + 1}", ", ".join(f"{k}={v}" for k, v in sorted(rest.items()))))
    num = getattr(ctx.config, "numerics", None)
    if num is not None:
        d = dataclasses.asdict(num) if dataclasses.is_dataclass(num) else {}
        rows.append(("numerics (config 1)", ", ".join(f"{k}={v}" for k, v in d.items()) or str(num)))
    rows.append(("comparison", f"grid {ctx.grid_dt:g} s; interactive plots decimated to ≤ {ctx.max_points} points "
                               "per trace (min/max envelopes); CSV at full grid resolution"))
    return rows


def provenance(ctx: ReportContext) -> list[tuple[str, list[tuple[str, str]]]]:
    """The provenance tables in page order: (title, rows)."""
    return [("Files", file_rows(ctx)), ("Pump configuration and calibration", pump_rows(ctx)),
            ("Software", software_rows(ctx)), ("Model and numerics", model_rows(ctx))]
