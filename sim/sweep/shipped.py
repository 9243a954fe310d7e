"""Shipped sweep results: a sweep's table in the package, keyed by content.

``sim/sweep/results/NAME.json`` holds what ``rvsm sweep report`` reads of a sweep's
database (every result row's metrics and design, every design's lane cost, the sweep
file's text) and its :func:`~rvsm.sim.sweep.shipped_key.results_key`, so that ``rvsm
sweep report --camera HxW`` answers at once on a fresh clone. :func:`open_results` opens
either a results database or such a table; a table whose key is not today's (the sweep
file, the twins or the RTL and cost model changed) is refused with one line naming
:data:`REMAKE`, the command that remakes it (:func:`remake`: the real sweep into
``build/sweep-results/``, then :func:`export_table`).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.shipped_key import PARTS, results_key, twin_sources_digest
from rvsm.sim.sweep.spec import SweepSpec, load_sweep, parse_sweep
from rvsm.sim.sweep.store import METRICS, SweepStore, open_existing

__all__ = ["DEFAULT_TABLE", "REMAKE", "SHIPPED_DIR", "ShippedResults", "StaleResults",
           "export_table", "load_table", "open_results", "remake", "remake_database"]

#: Where shipped tables live (package data of ``rvsm.sim.sweep``).
SHIPPED_DIR = Path(__file__).parent / "results"
#: The table ``rvsm sweep report`` reads without a database: the ECP5-85 search behind
#: docs/design-space.md (``sweeps/ecp5-85-40khz.toml``).
DEFAULT_TABLE = SHIPPED_DIR / "ecp5-85-40khz.json"
#: The command that remakes the shipped tables (Makefile target ``sweep-results``).
REMAKE = "make sweep-results"
FORMAT = 1
#: The source tree (for the sweep file a table names, when it is there).
_ROOT = Path(__file__).resolve().parents[2]
_ROW_KEYS = ("point_id", "design_id", "scene", "noise", "seed", "steps", "size", "model",
             "status", "error", *METRICS, "seconds", "scene_digest")


class StaleResults(RvsmError):
    """Shipped results computed by other code than today's (exit 2, naming :data:`REMAKE`)."""


@dataclass
class ShippedResults:
    """A loaded table: rows as :meth:`SweepStore.results` gives them (``record`` None)."""

    path: Path
    sweep_path: str
    sweep_text: str
    key: dict[str, str]
    made: str
    seconds: float
    rows: list[dict[str, Any]]

    def results(self, status: str | None = None) -> list[dict[str, Any]]:
        """The rows (copies), of ``status`` only when given."""
        return [dict(r) for r in self.rows if status is None or r["status"] == status]

    def sweeps(self) -> list[tuple[str, str]]:
        """``(sweep_hash, path)`` of the one sweep the table holds."""
        return [(hashlib.sha256(self.sweep_text.encode()).hexdigest()[:16], self.sweep_path)]

    def sweep_texts(self) -> list[tuple[str, str]]:
        """``(path, text)`` of the sweep file."""
        return [(self.sweep_path, self.sweep_text)]

    def spec(self) -> SweepSpec:
        """The sweep file as today's code parses it."""
        base = _ROOT / Path(self.sweep_path).parent
        return parse_sweep(self.sweep_text, self.sweep_path,
                           base_dir=base if base.is_dir() else None)

    def describe(self) -> str:
        """``"shipped results X.json (sweeps/Y.toml, made ...)"``: one line for the CLI."""
        return (f"shipped results {_shown(self.path)} ({self.sweep_path}, made {self.made}; "
                f"key matches today's code)")

    def close(self) -> None:
        """Nothing to close (the table is in memory)."""

    def __enter__(self) -> ShippedResults:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _shown(path: Path) -> str:
    try:
        return path.resolve().relative_to(_ROOT).as_posix()
    except ValueError:
        return str(path)


def export_table(db: str | os.PathLike, spec: SweepSpec, out: str | os.PathLike,
                 seconds: float = 0.0) -> Path:
    """Write ``spec``'s rows of the database ``db`` (and their lane costs) with today's
    key to ``out`` (JSON, atomically). :class:`RvsmError` when a row is missing or
    failed: a table must hold the whole sweep."""
    ids = {t.point_id for t in spec.tasks()}
    with open_existing(db) as store:
        rows = [r for r in store.results() if r["point_id"] in ids]
    missing = len(ids) - len({r["point_id"] for r in rows if r["status"] != "error"})
    if missing:
        raise RvsmError(f"{db}: {missing} of {len(ids)} row(s) of {spec.source} are missing "
                        "or failed; rerun the sweep before exporting")
    designs, lane_cost, out_rows = {}, {}, []
    for r in rows:
        designs.setdefault(r["design_id"], {"toml": r["design_toml"], "axes": r["axes"],
                                            "hw_digest": r["hw_digest"]})
        if r["hw_digest"] and r["hw_record"]:
            lane_cost[r["hw_digest"]] = {k: r[k] for k in (
                "lut4_per_lane", "ff_per_lane", "lut4_base", "fmax_mhz", "hw_size",
                "hw_lanes")} | {"record": json.loads(r["hw_record"])}
        out_rows.append({k: r[k] for k in _ROW_KEYS})
    try:
        sweep_path = Path(spec.source).resolve().relative_to(_ROOT).as_posix()
    except ValueError:
        sweep_path = Path(spec.source).name
    table = {"format": FORMAT, "sweep": {"path": sweep_path, "text": spec.text},
             "key": results_key(spec), "remake": REMAKE,
             "made": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
             "seconds": round(seconds, 1), "designs": designs, "lane_cost": lane_cost,
             "rows": sorted(out_rows, key=lambda r: (r["design_id"], r["scene"], r["noise"],
                                                     r["seed"]))}
    write_text_atomic(Path(out), json.dumps(table, indent=1, sort_keys=True) + "\n")
    return Path(out)


def load_table(path: str | os.PathLike) -> ShippedResults:
    """Read a table written by :func:`export_table` (not checked against today's code:
    :func:`check_key` does that). :class:`RvsmError` naming ``path`` when unreadable."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
        if data.get("format") != FORMAT:
            raise ValueError(f"format {data.get('format')!r}, expected {FORMAT}")
        designs, costs = data["designs"], data["lane_cost"]
        rows = []
        for r in data["rows"]:
            d = designs[r["design_id"]]
            hw = costs.get(d["hw_digest"] or "", {})
            rows.append({**r, "noise": bool(r["noise"]), "axes": d["axes"],
                         "design_toml": d["toml"], "hw_digest": d["hw_digest"],
                         "record": None, **{k: hw.get(k) for k in (
                             "lut4_per_lane", "ff_per_lane", "lut4_base", "fmax_mhz",
                             "hw_size", "hw_lanes")},
                         "hw_record": hw["record"] if hw else None})
        return ShippedResults(p, data["sweep"]["path"], data["sweep"]["text"], data["key"],
                              data["made"], float(data["seconds"]), rows)
    except FileNotFoundError:
        raise RvsmError(f"{_shown(p)}: no such shipped results table; remake the shipped tables "
                        f"with `{REMAKE}`") from None
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise RvsmError(f"{_shown(p)}: not a shipped sweep results table ({exc}); remake it with "
                        f"`{REMAKE}`") from None


def check_key(table: ShippedResults) -> None:
    """:class:`StaleResults` (one line: what changed and :data:`REMAKE`) unless today's
    code would compute ``table`` again: its sweep file (as the source tree has it, when
    it does) and today's :func:`results_key` of it equal the table's."""
    here = _ROOT / table.sweep_path
    changed = []
    if here.is_file() and here.read_text(encoding="utf-8") != table.sweep_text:
        changed.append(table.sweep_path)
    current = results_key(table.spec())
    changed += [PARTS[k] for k in PARTS if current.get(k) != table.key.get(k)
                and not (k == "sweep" and changed)]
    if changed:
        raise StaleResults(
            f"{_shown(table.path)}: the shipped sweep results no longer match the code: "
            f"{' and '.join(changed)} changed since they were made ({table.made}); remake "
            f"them with `{REMAKE}` "
            f"(the sweep, about 12 min on 2 cores) or run the sweep yourself: rvsm sweep "
            f"{table.sweep_path} -o build/{Path(table.sweep_path).stem}.sqlite")


def open_results(path: str | os.PathLike | None = None) -> SweepStore | ShippedResults:
    """A results database (``*.sqlite``), or a shipped table (``*.json``; None: the
    default, :data:`DEFAULT_TABLE`) checked against today's code (:func:`check_key`)."""
    if path is not None and Path(path).suffix.lower() != ".json":
        return open_existing(path)
    table = load_table(DEFAULT_TABLE if path is None else path)
    check_key(table)
    return table


def remake_database(spec: SweepSpec) -> Path:
    """Where :func:`remake` keeps ``spec``'s rows: ``build/sweep-results/STEM-TWIN.sqlite``
    (TWIN: :func:`twin_sources_digest`, so a change of the twins starts a new database
    and recomputes every row, while a change under ``rtl/`` only re-synthesises)."""
    return Path("build") / "sweep-results" / \
        f"{Path(spec.source).stem}-{twin_sources_digest()}.sqlite"


def remake(sweep_file: str | os.PathLike, out: str | os.PathLike | None = None,
           workers: int | None = None, progress: bool = True) -> tuple[Path, Any]:
    """Run the real sweep of ``sweep_file`` (only what :func:`remake_database` lacks) and
    export its table to ``out`` (default ``SHIPPED_DIR/STEM.json``). Returns the table's
    path and the run's :class:`~rvsm.sim.sweep.run.SweepSummary`; nothing is exported
    when a row failed."""
    from rvsm.sim.sweep.run import run_sweep

    spec = load_sweep(sweep_file)
    db = remake_database(spec)
    summary = run_sweep(spec, db, workers=workers, progress=progress)
    target = Path(out) if out else SHIPPED_DIR / f"{Path(sweep_file).stem}.json"
    if not summary.errors:
        export_table(db, spec, target, summary.seconds)
    return target, summary
