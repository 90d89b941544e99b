"""Append-only JSON-lines store of finished tasks (sweep points, batch recordings): resumable.

One line per finished task, written and flushed (``fsync``) as soon as it is
known, so an interrupted run loses at most the tasks that were in flight.  Each
record carries its task ``id``; :meth:`ResultStore.add` refuses a second record
for an id already stored, which is what makes every task appear exactly once even
when the engine computed it twice (a worker died after finishing but before its
result was collected).  A last line cut by a crash is dropped on open (and the
file truncated to the last complete record), so a resumed run recomputes it.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

__all__ = ["ResultStore"]


def _clean(value):
    """JSON-ready copy: NaN/inf become None (JSON has no NaN), numpy scalars become Python numbers."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class ResultStore:
    """The records of one run in ``path`` (JSON lines), keyed by ``record["id"]``.

    Parameters
    ----------
    path : path
        The ``.jsonl`` file; created if missing, else read (resume).
    """

    def __init__(self, path):
        self.path = Path(path)
        self.records: dict[str, dict] = {}
        self.dropped_tail = 0          #: bytes of a cut last line removed on open
        if self.path.exists():
            self._load()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fh = open(self.path, "a", encoding="utf-8")

    def _load(self) -> None:
        data = self.path.read_bytes()
        good = 0
        for line in data.splitlines(keepends=True):
            if not line.endswith(b"\n"):
                break
            try:
                rec = json.loads(line)
            except ValueError:
                break
            self.records.setdefault(str(rec["id"]), rec)
            good += len(line)
        if good < len(data):
            self.dropped_tail = len(data) - good
            with open(self.path, "r+b") as fh:
                fh.truncate(good)

    def __contains__(self, task_id: str) -> bool:
        return task_id in self.records

    def __len__(self) -> int:
        return len(self.records)

    def add(self, record: dict) -> bool:
        """Append ``record`` (must hold ``id``); False (nothing written) if that id is stored already."""
        task_id = str(record["id"])
        if task_id in self.records:
            return False
        rec = _clean(record)
        self._fh.write(json.dumps(rec, allow_nan=False) + "\n")
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self.records[task_id] = rec
        return True

    def close(self) -> None:
        self._fh.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
