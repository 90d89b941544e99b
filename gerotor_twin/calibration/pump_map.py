"""A pump's published steady map (CSV) as operating points a fit can use (``calibrate --map F.csv``).

One row per steady operating point; one column per quantity, its unit in brackets in the
header (``speed [rpm]``).  Lines starting with ``#`` are comments; blank lines are skipped.

==========================  ===================================  ===========================
quantity (header names)     units                                required
==========================  ===================================  ===========================
speed (``speed``, ``n``)    ``rpm``, ``1/min``, ``rad/s``        yes
delivery pressure           ``bar``, ``kPa``, ``MPa``, ``Pa``,   yes (gauge; ``bar abs``,
(``p_delivery``, ``p_d``)   ``psi`` (``psig``)                   ``kPa abs``, ``MPa abs``,
                                                                 ``Pa abs``, ``psia``: absolute)
suction pressure            as the delivery pressure             no (default: the pump
(``p_suction``, ``p_s``)                                         config's suction pressure)
oil temperature             ``degC``, ``°C``, ``K``, ``degF``,   yes
(``T_oil``, ``oil_temperature``) ``°F``
flow (``Q``, ``flow``)      ``l/min`` (``lpm``), ``m3/s``,       one of flow and η_v
                            ``cm3/s``, ``gpm`` (US gallons per
                            minute, ``gal/min``)
volumetric efficiency       ``-``, ``%``                         one of flow and η_v
(``eta_v``, ``eta``)
==========================  ===================================  ===========================

The cells are separated by commas, or by semicolons or tabs (a spreadsheet saved where the comma is the
decimal sign: the separator is the header line's, and with semicolons or tabs a number may have a
decimal comma, ``12,5``).

Every value is converted to SI on reading; a volumetric efficiency becomes a flow with the
prior config's displacement:

.. math::
    Q = \\eta_v \\, D \\, \\frac{\\omega}{2\\pi}

(``D`` [m³/rev] of the ideal profiles), so ``η_v`` in the file must be relative to the same
displacement.  Each row becomes a :class:`~.plateaus.PlateauRecord` (no time span, no
standard error: its weight in the fit is the model-error floor, ``calibrate --flow-floor``).
A bad row is reported on one line naming the row, the column, the value and the allowed
range; all bad rows are reported together (:class:`PumpMapError`).
"""
from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, clip
from .plateaus import PlateauRecord

__all__ = ["PumpMapError", "MapLimits", "read_map", "UNITS"]

#: header names (lower case) of each quantity
NAMES = {"speed": ("speed", "n", "shaft_speed"),
         "p_delivery": ("p_delivery", "p_d", "delivery_pressure"),
         "p_suction": ("p_suction", "p_s", "suction_pressure"),
         "t_oil": ("t_oil", "oil_temperature", "temperature"),
         "flow": ("q", "flow", "delivery_flow"),
         "eta_v": ("eta_v", "eta", "volumetric_efficiency")}

_PSI = 6894.757293168          #: the pound-force per square inch [Pa]
_GALLON = 3.785411784e-3        #: the US gallon [m³]
_PRESSURE = {"bar": (1e5, False), "kpa": (1e3, False), "mpa": (1e6, False), "pa": (1.0, False),
             "psi": (_PSI, False), "psig": (_PSI, False), "bar abs": (1e5, True), "kpa abs": (1e3, True),
             "mpa abs": (1e6, True), "pa abs": (1.0, True), "psia": (_PSI, True), "psi abs": (_PSI, True)}
#: per quantity: unit (lower case) → (scale to SI, offset added after scaling) [SI]
UNITS = {"speed": {"rpm": (2 * math.pi / 60, 0.0), "1/min": (2 * math.pi / 60, 0.0), "rad/s": (1.0, 0.0)},
         "t_oil": {"degc": (1.0, 0.0), "°c": (1.0, 0.0), "k": (1.0, -273.15),
                   "degf": (5.0 / 9.0, -160.0 / 9.0), "°f": (5.0 / 9.0, -160.0 / 9.0)},   # (F − 32)·5/9
         "flow": {"l/min": (1e-3 / 60, 0.0), "lpm": (1e-3 / 60, 0.0), "m3/s": (1.0, 0.0), "cm3/s": (1e-6, 0.0),
                  "gpm": (_GALLON / 60, 0.0), "gal/min": (_GALLON / 60, 0.0)},
         "eta_v": {"-": (1.0, 0.0), "%": (0.01, 0.0)}}
_HEADER = re.compile(r"^\s*([^\[\]]+?)\s*\[([^\]]*)\]\s*$")


class PumpMapError(InputError):
    """One or more bad rows of a map; ``lines``: one message per bad row."""

    def __init__(self, lines: list[str]):
        self.lines = list(lines)
        super().__init__("map", f"{len(lines)} bad row(s)", "see the lines above", lines[0] if lines else "")


@dataclass(frozen=True)
class MapLimits:
    """What the pump and the model allow (SI), from the prior pump config."""
    displacement_m3: float       #: volume per revolution of the ideal profiles [m³]
    p_atm_pa: float              #: atmospheric pressure (gauge zero) [Pa]
    max_speed_rad_s: float       #: top of the speed range [rad/s]
    max_delivery_pa: float       #: top of the delivery range, gauge [Pa]
    t_oil_c: tuple[float, float] = (-40.0, 200.0)   #: oil temperature allowed [°C]
    eta_max: float = 1.1         #: largest volumetric efficiency accepted (measurement scatter) [-]
    #: the config's rated maxima (rpm, bar gauge) the two tops widen (:func:`.records.widened`); None: the tops
    #: are the range itself
    rated: tuple[float, float] | None = None

    @classmethod
    def from_config(cls, cfg) -> "MapLimits":
        """The limits of the model's input envelope for ``cfg``: its rated speed and delivery pressure + 10 %
        (:data:`.records.RANGE_MARGIN`), as the twin runs them (:func:`.records.check_inputs`)."""
        from ..model.records import widened          # the kernel's module: imported only when a config is read
        rng = cfg.range
        return cls(cfg.gears.displacement_closed_form(), cfg.fluid.atmospheric_pa,
                   widened(rng.max_speed_rpm) * 2 * math.pi / 60, widened(rng.max_delivery_bar) * 1e5,
                   rated=(rng.max_speed_rpm, rng.max_delivery_bar))

    def range_note(self, quantity: str) -> str:
        """How an error names the top of the speed or delivery-pressure range."""
        if self.rated is None:
            return "the pump config's range"
        from ..model.records import widened_text
        return widened_text(*((self.rated[0], "rpm") if quantity == "speed" else (self.rated[1], "bar")))


@dataclass(frozen=True)
class _Column:
    quantity: str
    index: int
    header: str
    unit: str
    scale: float
    offset: float
    absolute: bool = False       #: pressures only: the column is absolute, not gauge

    def si(self, v: float, p_atm: float) -> float:
        x = v * self.scale + self.offset
        return x + p_atm if self.quantity.startswith("p_") and not self.absolute else x

    def from_si(self, x: float, p_atm: float) -> float:
        if self.quantity.startswith("p_") and not self.absolute:
            x -= p_atm
        return (x - self.offset) / self.scale


def _column(path: Path, i: int, header: str) -> _Column | None:
    """The quantity and unit of one header cell (None: a column the map does not use)."""
    m = _HEADER.match(header)
    name = (m.group(1) if m else header).strip().lower()
    quantity = next((q for q, names in NAMES.items() if name in names), None)
    if quantity is None:
        return None
    if not m:
        raise InputError(f"{path.name}: column {i + 1}", header, f"'{name} [unit]' with the unit in brackets")
    unit = " ".join(m.group(2).strip().lower().split())
    table = _PRESSURE if quantity.startswith("p_") else UNITS[quantity]
    if unit not in table:
        raise InputError(f"{path.name}: column {i + 1} ({name}) unit", m.group(2), " | ".join(table))
    if quantity.startswith("p_"):
        scale, absolute = table[unit]
        return _Column(quantity, i, header.strip(), m.group(2).strip(), scale, 0.0, absolute)
    scale, offset = table[unit]
    return _Column(quantity, i, header.strip(), m.group(2).strip(), scale, offset)


def _columns(path: Path, header: list[str]) -> dict[str, _Column]:
    cols: dict[str, _Column] = {}
    for i, h in enumerate(header):
        c = _column(path, i, h)
        if c is None:
            continue
        if c.quantity in cols:
            raise InputError(f"{path.name}: column {i + 1}", h, f"one column of {c.quantity}")
        cols[c.quantity] = c
    for q in ("speed", "p_delivery", "t_oil"):
        if q not in cols:
            raise InputError(f"{path.name}: header", ", ".join(header), f"a column {NAMES[q][0]} [unit]")
    if ("flow" in cols) == ("eta_v" in cols):
        raise InputError(f"{path.name}: header", ", ".join(header), "exactly one of Q [unit] and eta_v [unit]")
    return cols


def _bounds(q: str, lim: MapLimits, speed: float) -> tuple[float, float, bool]:
    """(low, high, low open) of quantity ``q`` in SI (pressures absolute)."""
    qth = lim.displacement_m3 * speed / (2 * math.pi)
    return {"speed": (0.0, lim.max_speed_rad_s, True),
            "p_delivery": (lim.p_atm_pa, lim.p_atm_pa + lim.max_delivery_pa, False),
            "p_suction": (1e4, lim.p_atm_pa + 1e6, False),
            "t_oil": (*lim.t_oil_c, False),
            "flow": (0.0, lim.eta_max * qth, True),
            "eta_v": (0.0, lim.eta_max, True)}[q]


def _delimiter(header: str) -> str:
    """The cell separator of a map: the header line's semicolon or tab, else the comma."""
    return next((d for d in (";", "\t") if d in header), ",")


def _number(text: str, decimal_comma: bool) -> float:
    """``text`` as a float; with ``decimal_comma`` (a file separated by semicolons or tabs) ``12,5`` is 12.5."""
    if decimal_comma and text.count(",") == 1 and "." not in text:
        text = text.replace(",", ".")
    return float(text)


def _check(col: _Column, text: str, lim: MapLimits, speed: float,
           decimal_comma: bool = False) -> tuple[float, str | None]:
    """(SI value, None) or (NaN, the reason: allowed range in the column's unit)."""
    lo, hi, lo_open = _bounds(col.quantity, lim, speed)
    a, b = sorted((col.from_si(lo, lim.p_atm_pa), col.from_si(hi, lim.p_atm_pa)))
    allowed = f"{'(' if lo_open else '['}{a:.6g}, {b:.6g}] {col.unit}"
    if col.quantity == "flow":
        allowed += f" (up to η_v {lim.eta_max:g} at this speed)"
    elif col.quantity in ("speed", "p_delivery"):
        allowed += f" ({lim.range_note(col.quantity)})"
    try:
        v = _number(text, decimal_comma)
    except ValueError:
        return math.nan, f"a number in {allowed}"
    x = col.si(v, lim.p_atm_pa)
    ok = math.isfinite(x) and (lo < x if lo_open else lo <= x) and x <= hi * (1 + 1e-12)
    return (x, None) if ok else (math.nan, allowed)


def _row(path: Path, row: int, line: int, cells: list[str], cols: dict[str, _Column], lim: MapLimits,
         decimal_comma: bool = False):
    """(PlateauRecord, None) or (None, the one-line complaint)."""
    order = ["speed"] + [q for q in ("p_delivery", "p_suction", "t_oil", "flow", "eta_v") if q in cols]
    vals = {}
    for q in order:
        c = cols[q]
        text = cells[c.index].strip() if c.index < len(cells) else ""
        x, bad = _check(c, text, lim, vals.get("speed", math.nan), decimal_comma)
        if bad is not None:
            return None, str(InputError(f"{path.name} row {row} (line {line}): {c.header}", clip(text, 40), bad))
        vals[q] = x
    qth = lim.displacement_m3 * vals["speed"] / (2 * math.pi)
    flow = vals["flow"] if "flow" in vals else vals["eta_v"] * qth
    return PlateauRecord(bag=str(path), index=row, t0_s=math.nan, t1_s=math.nan, omega=vals["speed"],
                         p_delivery_pa=vals["p_delivery"], p_suction_pa=vals.get("p_suction", math.nan),
                         oil_temperature_c=vals["t_oil"], flow_m3s=flow, flow_sem_m3s=math.nan, bins=1), None


def read_map(path, limits: MapLimits) -> list[PlateauRecord]:
    """The operating points of a map file (see the module doc), in SI.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    limits : MapLimits
        The prior pump's displacement and ranges (:meth:`MapLimits.from_config`).

    Raises
    ------
    InputError
        The header lacks a required column, names a unit not listed, or the file has no row.
    PumpMapError
        Bad rows: ``lines`` holds one message per row (row number, line number, column, value, allowed range).
    """
    path = Path(path)
    lines = path.read_text(encoding="utf-8-sig").splitlines()
    numbered = [(k + 1, s) for k, s in enumerate(lines) if s.strip() and not s.lstrip().startswith("#")]
    if not numbered:
        raise InputError(str(path), "an empty file", "a header line and one row per operating point")
    sep = _delimiter(numbered[0][1])
    parsed = list(csv.reader([s for _, s in numbered], delimiter=sep))
    cols = _columns(path, parsed[0])
    records, bad = [], []
    for row, ((line, _), cells) in enumerate(zip(numbered[1:], parsed[1:]), start=1):
        rec, why = _row(path, row, line, cells, cols, limits, sep != ",")
        (bad.append(why) if why else records.append(rec))
    if bad:
        raise PumpMapError(bad)
    if not records:
        raise InputError(str(path), "a header only", "one row per operating point below the header")
    return records
