"""The twin node's MCAP log policy: files, crash recovery, decimation, status (no rclpy).

:class:`NodeLogFiles` is what ``twin_node`` does with its log, kept out of the
node so the node only wires it:

* :meth:`NodeLogFiles.open` recovers the unfinalised logs of a crashed run in
  ``log_dir`` (``gerotor-twin log recover`` in a low-priority child process,
  beside the originals, logged), then
  opens a :class:`~gerotor_twin.io.background.BackgroundMcapLog` flushed every
  ``log_flush_s`` that resumes in a new file after a write error (disk full)
  once ``log_min_free_mb`` are free (checked every ``log_retry_s``);
* :meth:`NodeLogFiles.due` decides which outputs go to the log
  (``log_outputs_every``, ``log_waveform_every``, ``log_diagnostics_every``,
  ``log_summary_values``; inputs, ``twin/flow_summary`` and ``twin/flow_residual`` always);
* :meth:`NodeLogFiles.status` gives the log's part of the node's /diagnostics
  status (ERROR while the log cannot be written).

See docs/node.md.
"""
from __future__ import annotations

import datetime as _dt
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any, Callable, Iterable

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.twin.outputs import CHAMBER_WAVEFORM, DIAGNOSTICS_TOPIC, VALUE_TOPICS, is_instant

__all__ = ["NodeLogFiles", "log_directory"]


def log_directory(value: str) -> Path:
    """The ``log_dir`` parameter as a path: ``~`` and ``$VARS`` (e.g. ``$ROS_HOME``) expanded.

    Raises
    ------
    InputError
        A ``$VAR`` in it is not set.
    """
    expanded = os.path.expandvars(value)
    if "$" in expanded:
        raise InputError("log_dir", value, "a path whose environment variables are all set",
                         f"after expansion: {expanded}")
    return Path(expanded).expanduser()


def _os_reason(exc: OSError) -> str:
    """``[Errno 30] Read-only file system: '/x'`` as ``read-only file system: /x``."""
    why = (exc.strerror or type(exc).__name__).lower()
    return f"{why}: {exc.filename}" if exc.filename else why


class NodeLogFiles:
    """Log policy of one node run.

    Parameters
    ----------
    prm : dict
        The node's parameter values (:mod:`gerotor_twin.ros.params`).
    logger : object
        With ``info``, ``warning``, ``error`` (the node's rclpy logger).
    metadata : callable
        Returns the Metadata records of a new file (pump config, parameters, settings).

    Attributes
    ----------
    before_clock : int
        Inputs received before the clock was valid (not logged) [-].
    recovered : list of str
        Files recovered at start.
    """

    def __init__(self, prm: dict, logger: Any, metadata: Callable[[], dict]):
        self.prm = prm
        self.logger = logger
        self._metadata = metadata
        self._counts: dict[str, int] = {}
        self._diag_level = -1
        self._files = 0
        self.before_clock = 0
        self.recovered: list[str] = []

    # ------------------------------------------------------------------ files
    def open(self, topics: Iterable[tuple[str, str, str]]):
        """Recover crashed runs' logs, open the log, register ``(topic, msgtype, qos)``; None if off."""
        prm = self.prm
        if not prm["log_dir"]:
            return None
        from gerotor_twin.io import BackgroundMcapLog
        from gerotor_twin.io.background import Reopen
        directory = log_directory(prm["log_dir"])
        try:
            directory.mkdir(parents=True, exist_ok=True)
            self.recover_crashed(directory)
            first = self.new_file(directory)
        except OSError as exc:          # read-only, no permission, a file in the way, disk full...
            raise InputError("log_dir", prm["log_dir"], "a directory this process can create and write "
                             "files in ('' = no log)", _os_reason(exc)) from None
        reopen = Reopen(lambda: self.new_file(directory), directory, int(prm["log_min_free_mb"] * 1e6),
                        prm["log_retry_s"])
        log = BackgroundMcapLog(first, max_queue=prm["log_queue"],
                                flush_interval_s=prm["log_flush_s"], fsync=prm["log_fsync"], reopen=reopen)
        for topic, msgtype, qos in topics:
            log.add_topic(topic, msgtype, qos=qos)
        return log

    def new_file(self, directory: Path):
        """A new MCAP file (or rotating set) in ``directory``; also called after a disk-full outage."""
        from gerotor_twin.io import McapLog, RotatingMcapLog
        prm = self.prm
        stem = "twin_" + _dt.datetime.now().strftime("%Y%m%d_%H%M%S") + f"_{os.getpid()}"
        stem += f"_r{self._files}" if self._files else ""
        self._files += 1
        opts = dict(compression=prm["log_compression"], metadata=self._metadata(),
                    chunk_size=prm["log_chunk_kb"] * 1024)
        if prm["log_rotate_mb"] > 0 or prm["log_rotate_s"] > 0:
            return RotatingMcapLog(directory, stem, max_bytes=int(prm["log_rotate_mb"] * 1e6) or None,
                                   max_duration_s=prm["log_rotate_s"] or None, **opts)
        return McapLog(directory / f"{stem}.mcap", **opts)

    def recover_crashed(self, directory: Path) -> None:
        """Unfinalised logs of a crashed run in ``directory``: recover them beside the originals."""
        from gerotor_twin.io.recover import unfinalised_logs
        files = unfinalised_logs(directory)
        if not files:
            return
        self.logger.warning(
            f"{len(files)} unfinalised MCAP log(s) of a crashed run in {directory} "
            f"({', '.join(p.name for p in files)}): recovering each beside the original as "
            "<name>.recovered.mcap (in the background)")
        threading.Thread(target=self._recover_files, args=(files,), name="mcap-recover", daemon=True).start()

    def _recover_files(self, files) -> None:
        """``gerotor-twin log recover`` per file in a child process at low priority.

        A separate process, so the copy (≈ 4 MB/s of log on the dev machine) never
        holds this process's GIL while the model runs in real time.
        """
        from gerotor_twin.io.recover import recovered_path
        for p in files:
            try:
                child = subprocess.Popen([sys.executable, "-m", "gerotor_twin", "log", "recover", str(p)],
                                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                try:
                    os.setpriority(os.PRIO_PROCESS, child.pid, 10)
                except OSError:
                    pass  # already finished, or not permitted: run at normal priority
                text = child.communicate()[0].strip()
            except OSError as exc:
                self.logger.error(f"could not recover {p}: {exc}")
                continue
            if child.returncode != 0:
                self.logger.error(f"could not recover {p}: {text[-500:]}")
                continue
            self.recovered.append(str(recovered_path(p)))
            self.logger.warning(text[-1000:])

    # ------------------------------------------------------------- decimation
    def logged(self, topic: str) -> bool:
        """Whether an output topic goes to the log at all."""
        if topic == CHAMBER_WAVEFORM:
            return self.prm["log_waveforms"]
        return topic not in VALUE_TOPICS or self.prm["log_summary_values"]

    def due(self, topic: str, diag: dict | None = None) -> bool:
        """Log this message? Every N-th waveform / instantaneous output / diagnostics message.

        Inputs, ``twin/flow_summary`` and ``twin/flow_residual`` are always logged; a /diagnostics message whose
        highest level differs from the last logged one is always logged.
        """
        if not self.logged(topic):
            return False
        every = {CHAMBER_WAVEFORM: self.prm["log_waveform_every"],
                 DIAGNOSTICS_TOPIC: self.prm["log_diagnostics_every"]}.get(
            topic, self.prm["log_outputs_every"] if is_instant(topic) else 1)
        n = self._counts[topic] = self._counts.get(topic, 0) + 1
        if topic == DIAGNOSTICS_TOPIC and diag is not None:
            level = max((int(st["level"]) for st in diag["status"]), default=0)
            changed, self._diag_level = level != self._diag_level, level
            return changed or (n - 1) % every == 0
        return (n - 1) % every == 0

    # ----------------------------------------------------------------- status
    def status(self, log) -> tuple[int, str, dict]:
        """Level, message and values of the log for the node's /diagnostics status."""
        values = {"log_recovered": ", ".join(self.recovered) or "none", "inputs_before_clock": self.before_clock}
        if log is None:
            values["log_path"] = "off"
            return m.DIAG_OK, "", values
        st = log.stats()
        values.update({"log_path": str(log.log.path), "log_written": st.written,
                       "log_queue_depth": log.queue_depth, "log_dropped": st.dropped,
                       "log_error": st.error or "", "log_resumed": st.resumed,
                       "log_unfinalised": ", ".join(str(p) for p in log.unfinalised) or "none"})
        if st.error:
            return m.DIAG_ERROR, (f"MCAP log not written: {st.error}; {st.lost} message(s) lost so far; "
                                  f"a new file starts when {self.prm['log_min_free_mb']:g} MB are free "
                                  f"(checked every {self.prm['log_retry_s']:g} s)"), values
        if st.dropped:
            why = f" (resumed after {st.last_error})" if st.last_error else ""
            return m.DIAG_WARN, f"MCAP log dropped {st.dropped} message(s){why}", values
        return m.DIAG_OK, "", values
