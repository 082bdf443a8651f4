"""Typed, versioned case records: what one finished case of a study wrote to disk.

A case record holds the case id and fingerprint, its grid parameters, the complete resolved
scene (``rodval.core.scene_file.scene_to_dict``: a record can be rerun without the study
file), the reference label, one ``RunRecord`` per model and the discrepancy rows. On disk it is
JSON with ``schema`` (``SCHEMA``) and ``checksum`` (SHA-256 of the canonical JSON of the other
fields): ``read_case`` verifies both, so a damaged, edited or incomplete file is reported
(``DamagedRecord`` naming the file and what is wrong) and never reused.

This module is the one reader of case files; tables, resume and reports go through it.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rodval.core.trajectory import Trajectory

#: Version of the case-record layout; a record of another version is recomputed. 3: each
#: run's stats carry its peaks (``SolverStats.peaks``), which a record of 2 lacks.
SCHEMA = 3


class DamagedRecord(ValueError):
    """A case file that cannot be used: unreadable, wrong schema, checksum mismatch or
    incomplete. The message names the file."""


@dataclass
class RunRecord:
    """One model's run within a case: its label (column in the tables), the model set-up
    time (s) and the trajectory (with its stats, settings, options and events)."""

    label: str
    setup_s: float
    trajectory: Trajectory
    #: the model's modes (``Modes.to_dict``) when the study asks for them, or why they failed
    modes: dict[str, Any] | None = None
    modes_error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        out = {
            "label": self.label,
            "setup_s": self.setup_s,
            "trajectory": self.trajectory.to_dict(),
        }
        if self.modes is not None:
            out["modes"] = self.modes
        if self.modes_error is not None:
            out["modes_error"] = self.modes_error
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RunRecord:
        return cls(
            label=str(d["label"]),
            setup_s=float(d["setup_s"]),
            trajectory=Trajectory.from_dict(d["trajectory"]),
            modes=d.get("modes"),
            modes_error=d.get("modes_error"),
        )

    @property
    def status(self) -> int:
        return self.trajectory.stats.status


@dataclass
class CaseRecord:
    """Everything the tables and the report need about one finished case."""

    case: str
    fingerprint: str
    params: dict[str, Any]
    scene: dict[str, Any]
    reference: str
    runs: list[RunRecord]
    discrepancies: list[dict[str, Any]]

    @property
    def n(self) -> int:
        return len(self.scene["chain"]["l"])

    @property
    def t_end(self) -> float:
        return float(self.scene["t_end"])

    @property
    def lengths(self) -> list[float]:
        return list(self.scene["chain"]["l"])

    def body(self) -> dict[str, Any]:
        return {
            "schema": SCHEMA,
            "case": self.case,
            "fingerprint": self.fingerprint,
            "params": self.params,
            "scene": self.scene,
            "reference": self.reference,
            "runs": [r.to_dict() for r in self.runs],
            "discrepancies": self.discrepancies,
        }

    def to_json(self) -> str:
        body = self.body()
        return json.dumps({**body, "checksum": checksum(body)}, indent=1, default=_json_default)


def _json_default(value: Any) -> Any:
    if hasattr(value, "item"):
        return value.item()
    return repr(value)


def _canonical(body: dict[str, Any]) -> str:
    # the same text the file was checked with: round-trip through JSON first (floats, inf)
    return json.dumps(
        json.loads(json.dumps(body, default=_json_default)), sort_keys=True, separators=(",", ":")
    )


def checksum(body: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of a record's body (every field but the checksum)."""
    return hashlib.sha256(_canonical(body).encode()).hexdigest()


def read_case(path: Path, *, labels: list[str] | None = None) -> CaseRecord:
    """The case record in ``path``, verified: schema, checksum, and (when ``labels`` is
    given) one run for each of these model labels. DamagedRecord otherwise."""
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DamagedRecord(
            f"{path}: unreadable case record ({type(exc).__name__}: {exc})"
        ) from None
    if not isinstance(doc, dict):
        raise DamagedRecord(
            f"{path}: a case record must be a JSON object, got {type(doc).__name__}"
        )
    if doc.get("schema") != SCHEMA:
        raise DamagedRecord(f"{path}: case record schema {doc.get('schema')!r}, expected {SCHEMA}")
    body = {k: v for k, v in doc.items() if k != "checksum"}
    if doc.get("checksum") != checksum(body):
        raise DamagedRecord(f"{path}: checksum mismatch (the file was edited or damaged)")
    try:
        rec = CaseRecord(
            case=str(doc["case"]),
            fingerprint=str(doc["fingerprint"]),
            params=dict(doc["params"]),
            scene=dict(doc["scene"]),
            reference=str(doc["reference"]),
            runs=[RunRecord.from_dict(r) for r in doc["runs"]],
            discrepancies=list(doc["discrepancies"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise DamagedRecord(
            f"{path}: malformed case record ({type(exc).__name__}: {exc})"
        ) from None
    if labels is not None:
        have = [r.label for r in rec.runs]
        missing = [lab for lab in labels if lab not in have]
        if missing:
            raise DamagedRecord(f"{path}: incomplete case record: no run of model {missing[0]!r}")
    for run in rec.runs:
        for q, v in run.trajectory.values.items():
            if run.trajectory.success and not all(math.isfinite(x) for x in v.ravel()):
                raise DamagedRecord(
                    f"{path}: run {run.label!r} reports success with non-finite values of {q!r}"
                )
    return rec
