"""The evaluation cache: every evaluation of a design, on disk, named by its content.

An evaluation is one candidate schedule on one motion at one horizon. Its key is the
SHA-256 of the canonical JSON of everything its result depends on: the candidate (the
family's settings and the rounded variables, or the catalogue scheme), the motion
spec, the horizon (duration, output step, sources left out) and the error model
(site, constant errors, initial errors, vertical channel). Its record holds the
schedule's metrics (motor starts per hour, turning fraction, range) and, once
computed, the RMS.

The records are lines of ``OUT/evaluations.jsonl``, appended (and flushed) as each
result arrives, so an interrupted design keeps everything it finished; a line a
killed process left half-written is ignored on reading, and a later line of the same
key completes an earlier one. A design run again with the same output directory
replays the same seeded optimizer and finds its evaluations here: it gives the same
result at the cost of reading the file.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

from inserr.design.motions import canonical

FILE = "evaluations.jsonl"


def evaluation_key(candidate: dict[str, Any], motion_key: str, context: str) -> str:
    """Content address of one evaluation (hex SHA-256).

    Parameters
    ----------
    candidate : dict
        ``{"family": spec, "vars": [...]}`` or ``{"catalogue": name, ...}``.
    motion_key : str
        :attr:`inserr.design.motions.MotionCase.key`.
    context : str
        Canonical JSON of the horizon and the error model.
    """
    text = canonical({"candidate": candidate, "motion": motion_key, "context": context})
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


class EvaluationCache:
    """Records by key, kept in memory and (with a directory) appended to ``FILE``.

    Parameters
    ----------
    root : Path or None
        Directory of ``evaluations.jsonl`` (created on the first write); None keeps
        the records in memory only.
    """

    def __init__(self, root: Path | None = None):
        self.path = None if root is None else Path(root) / FILE
        self.records: dict[str, dict[str, Any]] = {}
        self.loaded = 0
        if self.path is not None and self.path.is_file():
            with open(self.path, encoding="utf-8") as f:
                for line in f:
                    try:
                        rec = json.loads(line)
                        key = rec["key"]
                    except (ValueError, KeyError, TypeError):
                        continue  # a line cut short by a killed run
                    self.records.setdefault(key, {}).update(rec)
            self.loaded = len(self.records)
        self._file = None

    def get(self, key: str) -> dict[str, Any] | None:
        """The record of ``key`` (``metrics``, ``rms_nmi`` when computed), or None."""
        return self.records.get(key)

    def put(self, key: str, record: dict[str, Any]) -> None:
        """Add (or complete) the record of ``key`` and append it to the file."""
        rec = {"key": key, **record}
        self.records.setdefault(key, {}).update(rec)
        if self.path is None:
            return
        if self._file is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 - closed by close()
        # One write per line: a killed process leaves whole lines and at most one cut one.
        self._file.write(json.dumps(rec, sort_keys=True, allow_nan=False) + "\n")
        self._file.flush()

    def sync(self) -> None:
        """Make the appended lines durable (once per batch, not per line)."""
        if self._file is not None:
            os.fsync(self._file.fileno())

    def close(self) -> None:
        """Flush and close the file."""
        if self._file is not None:
            self.sync()
            self._file.close()
            self._file = None
