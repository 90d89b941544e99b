"""Per-revolution outputs of the twin: flow summary and chamber-pressure waveform.

The clock driver splits the model advance at every whole shaft revolution and
hands the solver output to a :class:`RevolutionRecorder`:

* :meth:`RevolutionRecorder.record` appends the rows of an advance to the
  :class:`Revolution` in progress (angle since its start [rad], chamber
  pressures [Pa]);
* :meth:`RevolutionRecorder.complete` closes it at the boundary and returns
  the messages: ``twin/flow_summary`` (mean delivery over the revolution from
  the exact delivered volume [m³/s], theoretical = displacement / revolution
  time [m³/s], leakage = their difference [m³/s], volumetric efficiency [-])
  and, every ``waveform_every`` revolutions, the chamber-pressure waveform
  resampled on ``waveform_samples`` equally spaced angles; then starts the
  next revolution;
* :meth:`RevolutionRecorder.drop` forgets the revolution in progress (hold,
  lag skip, reset): the next boundary starts a new one without a summary.

A message with a non-finite value is never emitted; it is counted in
``nonfinite_suppressed``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gerotor_twin.model.pump import PumpState
from gerotor_twin.twin import outputs as O
from gerotor_twin.twin.outputs import OutputMessage

__all__ = ["Revolution", "RevolutionRecorder"]

_TWO_PI = 2.0 * math.pi
#: Rows kept per revolution before the recording is thinned by 2 (very slow revolutions) [-].
_MAX_ROWS = 200_000


@dataclass
class Revolution:
    """One shaft revolution in progress, from its start at a whole-turn boundary.

    Attributes
    ----------
    t0 : float
        Model time at its start [s].
    vol0 : float
        Delivered volume at its start [m³] (``PumpState.volumes[0]``).
    theta0 : float
        Shaft angle at its start [rad].
    theta : list of ndarray
        Angles since the start [rad], one array per recorded advance.
    p : list of ndarray
        Chamber pressures [Pa], one ``(rows, N)`` array per recorded advance.
    rows : int
        Rows recorded so far.
    lost_m3 : float
        Volume lost at the edge of the model since the start [m³] (:mod:`gerotor_twin.model.volumetric`).
    """
    t0: float
    vol0: float
    theta0: float
    theta: list = field(default_factory=list)
    p: list = field(default_factory=list)
    rows: int = 0
    lost_m3: float = 0.0

    @classmethod
    def start(cls, st: PumpState, n: int) -> "Revolution":
        """A revolution starting at state ``st`` (its first row: angle 0, the ``n`` chamber pressures)."""
        return cls(t0=st.t, vol0=float(st.volumes[0]), theta0=st.theta,
                   theta=[np.zeros(1)], p=[st.pressures[None, :n].copy()], rows=1)

    def append(self, theta, pressures) -> None:
        """Record rows: shaft angles [rad] and chamber pressures [Pa]; memory stays bounded."""
        self.theta.append(theta - self.theta0)
        self.p.append(pressures)
        self.rows += len(theta)
        if self.rows > _MAX_ROWS:             # very slow revolution: keep memory bounded
            self.theta = [np.concatenate(self.theta)[::2]]
            self.p = [np.concatenate(self.p)[::2]]
            self.rows = len(self.theta[0])

    def flow_summary(self, end: PumpState, displacement: float) -> tuple[float, float, float, float] | None:
        """(mean delivery [m³/s], theoretical [m³/s], leakage [m³/s], volumetric efficiency [-]) up to ``end``.

        ``displacement`` is the volume per revolution [m³]; the delivered volume is the model's less
        :attr:`lost_m3` (the edge losses, :mod:`gerotor_twin.model.volumetric`); None for a revolution of
        zero duration.
        """
        T = end.t - self.t0
        if not T > 0:
            return None
        dv = float(end.volumes[0] - self.vol0) - self.lost_m3
        q, qth = dv / T, displacement / T
        return q, qth, qth - q, dv / displacement

    def waveform_table(self, samples: int) -> np.ndarray | None:
        """Columns: angle [rad] on ``samples`` equal steps of one turn, then the N chamber pressures [Pa].

        None if fewer than two rows were recorded.
        """
        ang = np.concatenate(self.theta)
        p = np.concatenate(self.p)
        if ang.size < 2:
            return None
        n = p.shape[1]
        grid = np.arange(samples) * (_TWO_PI / samples)
        table = np.empty((samples, 1 + n))
        table[:, 0] = grid
        for j in range(n):
            table[:, 1 + j] = np.interp(grid, ang, p[:, j])
        return table


class RevolutionRecorder:
    """Records the revolution in progress and emits its summary and waveform at its end.

    Parameters
    ----------
    n_chambers : int
        Chambers of the pump (columns of the waveform).
    displacement : float
        Volume per revolution [m³].
    waveform_every : int
        A waveform every this many completed revolutions (0 = never).
    waveform_samples : int
        Angles of a waveform over one revolution.
    """

    def __init__(self, n_chambers: int, displacement: float, waveform_every: int, waveform_samples: int):
        self.N = n_chambers
        self.displacement = displacement
        self.waveform_every = waveform_every
        self.waveform_samples = waveform_samples
        self.current: Revolution | None = None
        self.revolutions = 0                  #: completed revolutions (with a revolution in progress)
        self.waveforms = 0                    #: waveforms emitted
        self.nonfinite_suppressed = 0         #: summaries / waveforms not emitted (non-finite)
        self.last_summary: tuple | None = None  #: last emitted flow summary (see :data:`~.outputs.SUMMARY_FIELDS`)

    def drop(self) -> None:
        """Forget the revolution in progress (no summary for it)."""
        self.current = None

    def add_loss(self, volume_m3: float) -> None:
        """Volume lost at the edge of the model [m³] during the last advance (none without a revolution)."""
        if self.current is not None:
            self.current.lost_m3 += volume_m3

    def record(self, out) -> None:
        """Append the rows of a solver output (``theta`` [rad], ``chamber_pressures`` [Pa])."""
        if self.current is not None:
            self.current.append(out.theta, out.chamber_pressures)

    def complete(self, st: PumpState, stamp_ns: int) -> list[OutputMessage]:
        """A whole revolution ended at ``st`` (stamp ``stamp_ns`` [ns]): its messages; the next one starts."""
        r = self.current
        msgs: list[OutputMessage] = []
        if r is not None:
            vals = r.flow_summary(st, self.displacement)
            if vals is not None:
                if O.all_finite(vals):
                    msgs.extend(O.summary_messages(stamp_ns, vals))
                    self.last_summary = vals
                else:
                    self.nonfinite_suppressed += 1
            self.revolutions += 1
            every = self.waveform_every
            if every and self.revolutions % every == 0:
                self._waveform(r, stamp_ns, msgs)
        self.current = Revolution.start(st, self.N)
        return msgs

    def _waveform(self, r: Revolution, stamp_ns: int, msgs: list[OutputMessage]) -> None:
        table = r.waveform_table(self.waveform_samples)
        if table is not None and O.all_finite(table):
            msgs.append(O.waveform(stamp_ns, table))
            self.waveforms += 1
        elif table is not None:
            self.nonfinite_suppressed += 1
