"""Sweep results in SQLite (WAL): one row per design point x scene x noise x seed.

Tables (see docs/design-space.md):

- ``sweeps``: every sweep file run into this database (hash, path, text, times).
- ``points``: every task a sweep expanded to, keyed by ``point_id``, with its design.
- ``results``: one row per finished task, primary key ``(point_id, scene, noise, seed,
  steps, size)``; ``status`` ``ok`` (metrics), ``invalid`` (validation refused the design;
  ``error`` says why) or ``error`` (the computation failed; retried on the next run). The
  full record (JSON) and the full design point (TOML) are stored with it, and
  ``scene_digest`` (:func:`rvsm.model.scene.digest.scene_digest`): the content of the
  scene the row was computed from, so a row whose scene file has since changed is
  recomputed, not reported as done (databases from before the column get it added,
  empty: their rows on scene files are recomputed once).
- ``lane_cost``: hardware cost per distinct RTL on the streaming array, keyed by its
  digest: logic (LUT4) and flip-flops per lane from yosys, optional Fmax, the memory bits
  of the design point (:func:`rvsm.rtl.fpga.lane_cost.lane_cost`). Databases of schema 1
  keep their old ``hw_cost`` table (fully parallel cells per pixel), no longer read.

Only the coordinating process writes, one transaction per row, so an interrupted sweep
keeps every finished row and a rerun adds exactly the missing ones.
"""

from __future__ import annotations

import json
import os
import sqlite3
import time
from pathlib import Path
from typing import Any

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.sim.sweep.spec import SweepSpec, SweepTask

SCHEMA_VERSION = 2
SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS sweeps (
    sweep_hash TEXT PRIMARY KEY, path TEXT NOT NULL, text TEXT NOT NULL,
    first_run TEXT NOT NULL, last_run TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS points (
    point_id TEXT PRIMARY KEY, design_id TEXT NOT NULL, sweep_hash TEXT NOT NULL,
    scene TEXT NOT NULL, noise INTEGER NOT NULL, seed INTEGER NOT NULL,
    steps INTEGER NOT NULL, size TEXT NOT NULL, axes TEXT NOT NULL,
    design_toml TEXT NOT NULL, hw_digest TEXT, error TEXT
);
CREATE TABLE IF NOT EXISTS results (
    point_id TEXT NOT NULL, scene TEXT NOT NULL, noise INTEGER NOT NULL,
    seed INTEGER NOT NULL, steps INTEGER NOT NULL, size TEXT NOT NULL,
    design_id TEXT NOT NULL, model TEXT, status TEXT NOT NULL, error TEXT,
    agreement REAL, psnr_float REAL, psnr_fixed REAL, psnr_cost REAL,
    ssim_float REAL, ssim_fixed REAL, ssim_cost REAL,
    mse_float REAL, mse_fixed REAL, mse_cost REAL, max_saturation_rate REAL,
    seconds REAL, axes TEXT NOT NULL, record TEXT, design_toml TEXT NOT NULL,
    hw_digest TEXT, finished TEXT NOT NULL, scene_digest TEXT,
    PRIMARY KEY (point_id, scene, noise, seed, steps, size)
);
CREATE INDEX IF NOT EXISTS results_design ON results (design_id);
CREATE TABLE IF NOT EXISTS lane_cost (
    digest TEXT PRIMARY KEY, size TEXT NOT NULL, lanes TEXT NOT NULL,
    lut4_per_lane REAL NOT NULL, ff_per_lane REAL NOT NULL, lut4_base REAL NOT NULL,
    fmax_mhz REAL, memory_bits INTEGER NOT NULL, seconds REAL NOT NULL,
    contract TEXT NOT NULL, record TEXT NOT NULL, finished TEXT NOT NULL
);
"""
METRICS = ("agreement", "psnr_float", "psnr_fixed", "psnr_cost", "ssim_float", "ssim_fixed",
           "ssim_cost", "mse_float", "mse_fixed", "mse_cost", "max_saturation_rate")


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S")


def database_error(exc: sqlite3.Error, path: str | os.PathLike,
                   what: str = "sweep database") -> RvsmError:
    """The one-line error for an SQLite failure on ``path``: a full disk or an I/O error
    is a :class:`ToolError` (exit 3); a read-only, unopenable or foreign file an
    :class:`RvsmError` (exit 2)."""
    code = getattr(exc, "sqlite_errorcode", 0) & 0xFF  # primary result code
    if code in (sqlite3.SQLITE_FULL, sqlite3.SQLITE_IOERR):
        why = "disk full" if code == sqlite3.SQLITE_FULL else f"{exc}; disk full?"
        return ToolError(f"{path}: the {what} cannot be written ({why}); free "
                         "space or choose another -o; finished rows are kept")
    if code in (sqlite3.SQLITE_READONLY, sqlite3.SQLITE_CANTOPEN, sqlite3.SQLITE_PERM):
        return RvsmError(f"{path}: cannot write the {what} ({exc}); choose a "
                         "writable -o")
    return RvsmError(f"{path}: not a usable {what}: {exc}")


def open_database(path: Path, schema: str) -> sqlite3.Connection:
    """``path`` opened (its folder made) in WAL mode with ``schema`` applied; SQLite
    errors propagate (map them with :func:`database_error`)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    db = sqlite3.connect(path, timeout=30)
    db.execute("PRAGMA journal_mode=WAL")
    db.execute("PRAGMA synchronous=NORMAL")
    db.executescript(schema)
    return db


class SweepStore:
    """An open results database (``path``; created with its schema if missing)."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        try:
            self.db = open_database(self.path, SCHEMA)
            columns = {r[1] for r in self.db.execute("PRAGMA table_info(results)")}
            if "scene_digest" not in columns:
                self.db.execute("ALTER TABLE results ADD COLUMN scene_digest TEXT")
            self.db.execute("INSERT OR IGNORE INTO meta VALUES ('schema_version', ?)",
                            (str(SCHEMA_VERSION),))
            self.db.commit()
        except sqlite3.DatabaseError as exc:
            raise database_error(exc, self.path) from None

    def close(self) -> None:
        """Close the connection."""
        self.db.close()

    def __enter__(self) -> SweepStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- writing ------------------------------------------------------------------------

    def register(self, spec: SweepSpec, tasks: list[SweepTask], digests: dict[str, str]) -> None:
        """Record the sweep file and its tasks (idempotent; one transaction)."""
        now = _now()
        with self.db:
            self.db.execute(
                "INSERT INTO sweeps VALUES (?, ?, ?, ?, ?) ON CONFLICT(sweep_hash) "
                "DO UPDATE SET last_run = excluded.last_run, path = excluded.path",
                (spec.sweep_hash, spec.source, spec.text, now, now),
            )
            self.db.executemany(
                "INSERT OR IGNORE INTO points VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                [(t.point_id, t.design.design_id, spec.sweep_hash, t.scene, int(t.noise),
                  t.seed, t.steps, t.size_text, json.dumps(t.design.axes), t.design.toml,
                  digests.get(t.design.design_id), t.design.error) for t in tasks],
            )

    def attach_digests(self, digests: dict[str, str]) -> None:
        """Point each design's rows at its hardware digest as this run computes it: rows
        stored without one (``[hardware]`` was off) and rows measured on older RTL or
        cost-model sources (the twins' rows stay valid; their lane cost is today's)."""
        with self.db:
            self.db.executemany(
                "UPDATE results SET hw_digest = ? WHERE design_id = ? AND "
                "hw_digest IS NOT ?", [(dig, did, dig) for did, dig in digests.items()],
            )

    def write_result(self, task: SweepTask, record: dict[str, Any] | None, status: str,
                     error: str | None = None, hw_digest: str | None = None,
                     scene_digest: str | None = None) -> bool:
        """Store one task's outcome; committed at once. Returns False if already stored
        (a finished row of the same scene content is never replaced; an ``error`` row,
        or a row computed from other scene content than ``scene_digest``, is)."""
        rec = record or {}
        row = (task.point_id, task.scene, int(task.noise), task.seed, task.steps,
               task.size_text, task.design.design_id, rec.get("model"), status, error,
               *[rec.get(m) for m in METRICS], rec.get("seconds"),
               json.dumps(task.design.axes), json.dumps(rec) if record else None,
               task.design.toml, hw_digest, _now(), scene_digest)
        with self.db:
            self.db.execute(
                "DELETE FROM results WHERE point_id = ? AND scene = ? AND noise = ? AND "
                "seed = ? AND steps = ? AND size = ? AND (status = 'error' OR "
                "scene_digest IS NOT ?)",
                (*row[:6], scene_digest),
            )
            cur = self.db.execute(
                f"INSERT OR IGNORE INTO results VALUES ({', '.join('?' * len(row))})", row
            )
        return cur.rowcount == 1

    def write_hw_cost(self, digest: str, stats: dict[str, Any]) -> None:
        """Store one hardware-cost result (``synthesise_task``'s record; ignored if the
        digest is already known)."""
        with self.db:
            self.db.execute(
                "INSERT OR IGNORE INTO lane_cost VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (digest, stats["size"], json.dumps(stats["lanes"]), stats["lut4_per_lane"],
                 stats["ff_per_lane"], stats["lut4_base"], stats.get("fmax_mhz"),
                 stats["memory_bits"], stats["seconds"], stats["contract"],
                 json.dumps(stats), _now()),
            )

    # -- reading ------------------------------------------------------------------------

    def done_keys(self) -> dict[tuple, str | None]:
        """Keys ``(point_id, scene, noise, seed, steps, size)`` of finished rows, each with
        the scene digest it was computed from (None: not recorded)."""
        cur = self.db.execute("SELECT point_id, scene, noise, seed, steps, size, scene_digest "
                              "FROM results WHERE status != 'error'")
        return {tuple(r[:6]): r[6] for r in cur}

    def known_digests(self) -> set[str]:
        """Hardware digests already measured."""
        return {r[0] for r in self.db.execute("SELECT digest FROM lane_cost")}

    def sweeps(self) -> list[tuple[str, str]]:
        """``(sweep_hash, path)`` of every sweep file run into this database."""
        return list(self.db.execute("SELECT sweep_hash, path FROM sweeps"))

    def sweep_texts(self) -> list[tuple[str, str]]:
        """``(path, text)`` of every sweep file run into this database, oldest run first."""
        return list(self.db.execute("SELECT path, text FROM sweeps ORDER BY last_run"))

    def results(self, status: str | None = None) -> list[dict[str, Any]]:
        """Result rows as dicts (``record`` and ``axes`` decoded), joined with lane_cost
        (its full record as ``hw_record``, JSON text)."""
        q = ("SELECT r.*, h.lut4_per_lane, h.ff_per_lane, h.lut4_base, h.fmax_mhz, "
             "h.size AS hw_size, h.lanes AS hw_lanes, h.record AS hw_record "
             "FROM results r LEFT JOIN lane_cost h ON h.digest = r.hw_digest")
        args: tuple = ()
        if status is not None:
            q += " WHERE r.status = ?"
            args = (status,)
        cur = self.db.execute(q + " ORDER BY r.rowid", args)
        cols = [c[0] for c in cur.description]
        rows = []
        for r in cur:
            d = dict(zip(cols, r, strict=True))
            d["axes"] = json.loads(d["axes"])
            d["record"] = json.loads(d["record"]) if d["record"] else None
            d["noise"] = bool(d["noise"])
            rows.append(d)
        return rows


def open_existing(path: str | os.PathLike) -> SweepStore:
    """Open a results database that must already exist (for reports)."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"{p}: no such results database; run `rvsm sweep SWEEP.toml -o {p}`")
    store = SweepStore(p)
    if not store.db.execute("SELECT 1 FROM meta WHERE key = 'schema_version'").fetchone():
        raise RvsmError(f"{p}: not a sweep results database")
    return store
