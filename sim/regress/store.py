"""The regression database: one row per run, keyed by the run's digest.

SQLite (WAL), written by the calling process only. ``runs`` holds every run of every
plan written into the file: its key (:attr:`~.plan.RunSpec.key`), plan, label, the
run's fields, ``status`` (``pass`` / ``fail`` / ``error``), figures, the first mismatch
and the functional coverage (JSON), the run folder, waveform and Verilator coverage
file. A run is written once under its key (``INSERT OR REPLACE``): a killed regression
resumes with the runs whose status is ``pass`` or ``fail`` skipped, and nothing is
counted twice; ``error`` rows are retried.
"""

from __future__ import annotations

import json
import os
import sqlite3
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.regress.plan import RunSpec
from rvsm.sim.sweep.store import database_error, open_database

__all__ = ["RegressionStore"]

SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE IF NOT EXISTS runs (
    key TEXT PRIMARY KEY, plan TEXT, label TEXT, stimulus TEXT, model TEXT, size TEXT,
    arch TEXT, lanes INTEGER, sim TEXT, harness TEXT, steps INTEGER, status TEXT,
    mismatches INTEGER, compared INTEGER, first_mismatch TEXT, coverage TEXT,
    cycles_per_second REAL, seconds REAL, run_dir TEXT, waves TEXT, error TEXT,
    finished TEXT, code_coverage TEXT
);
"""
DONE = ("pass", "fail")


class RegressionStore:
    """An open regression database at ``path`` (created with its schema if missing)."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        try:
            self.db = open_database(self.path, SCHEMA)
            self.db.execute("INSERT OR IGNORE INTO meta VALUES ('kind', 'rvsm regression')")
            kind = self.db.execute("SELECT value FROM meta WHERE key='kind'").fetchone()
            self.db.commit()
        except sqlite3.Error as exc:
            raise database_error(exc, self.path, "regression database") from None
        if kind is None or kind[0] != "rvsm regression":
            self.db.close()
            raise RvsmError(f"{self.path} is another kind of database; choose another -o")

    def close(self) -> None:
        """Close the connection."""
        self.db.close()

    def __enter__(self) -> RegressionStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def done_keys(self) -> set[str]:
        """Keys of runs finished with a verdict (``pass`` or ``fail``)."""
        return {r[0] for r in self.db.execute(
            f"SELECT key FROM runs WHERE status IN ({','.join('?' * len(DONE))})", DONE)}

    def write(self, spec: RunSpec, record: dict[str, Any]) -> None:
        """Record one run's outcome under its key (one transaction)."""
        j = json.dumps
        try:
            self._insert(spec, record, j)
        except sqlite3.Error as exc:
            raise database_error(exc, self.path, "regression database") from None

    def _insert(self, spec: RunSpec, record: dict[str, Any], j: Any) -> None:
        self.db.execute(
            "INSERT OR REPLACE INTO runs VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
            (spec.key, spec.plan, spec.label, spec.stimulus, spec.model,
             f"{spec.size[0]}x{spec.size[1]}", spec.arch, spec.lanes, spec.sim,
             spec.harness, spec.steps, record["status"], record.get("mismatches"),
             record.get("compared"), j(record.get("first_mismatch")),
             j(record.get("coverage")), record.get("cycles_per_second"),
             record.get("seconds"), record.get("run_dir"), record.get("waves"),
             record.get("error"), datetime.now(timezone.utc).isoformat(timespec="seconds"),
             record.get("code_coverage")))
        self.db.commit()

    def rows(self, keys: set[str] | None = None) -> list[dict[str, Any]]:
        """Every run (or those with ``keys``) as dicts, JSON columns decoded, by label."""
        cur = self.db.execute("SELECT * FROM runs ORDER BY label")
        names = [d[0] for d in cur.description]
        out = []
        for row in cur:
            d = dict(zip(names, row, strict=True))
            if keys is not None and d["key"] not in keys:
                continue
            for k in ("first_mismatch", "coverage"):
                d[k] = json.loads(d[k]) if d[k] else None
            out.append(d)
        return out
