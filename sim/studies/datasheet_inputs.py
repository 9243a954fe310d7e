"""What ``rvsm datasheet`` reads: the design point (with its ``[rtl]`` table) and the saved
results of other commands, each checked before anything is computed or written, and
:class:`DatasheetInputs`, everything the page is made from.

- the point TOML: the design point, and its ``[rtl]`` table read raw (``lanes``, ...),
  so the page can state the lanes the point was built for whether or not the loader
  knows that table;
- ``--fpga FILE.json``: ``rvsm fpga POINT --json`` (nextpnr's LUT4, FF, DP16KD, Fmax);
- ``--quality FILE.json``: ``rvsm quality POINT --json``;
- ``--verify FILE.json``: ``rvsm verify ... --json`` (spikes compared, mismatches);
- ``--formal FILE.json``: ``rvsm formal POINT --size HxW --json`` (each check's status);
- ``--mutate FILE.json``: ``rvsm mutate POINT --json`` (mutations killed, survivors);
- ``--regress FILE``: the results database of ``rvsm regress PLAN -o FILE.sqlite`` or its
  JUnit XML (``--junit FILE.xml``);
- ``--commands FILE.toml``: the command lines of saved results that do not record theirs.

A missing or malformed file is an :class:`~rvsm.model.infra.errors.RvsmError` naming it
(exit status 2), raised before the output folder is touched.
"""

from __future__ import annotations

import json
import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.text_files import read_utf8_text
from rvsm.rtl.fpga.devices import DeviceBudget
from rvsm.sim.studies.point_quality import PointQuality

__all__ = ["COMMAND_KEYS", "DatasheetInputs", "PointFile", "RegressSummary", "load_commands",
           "load_fpga_report", "load_point_file",
           "load_formal_report", "load_mutate_report",
           "load_regress", "load_regress_database", "load_regress_junit",
           "load_verify_result", "read_json_object", "read_result_text"]

#: Largest saved result read (bytes): these are summaries of a few kB.
MAX_RESULT_BYTES = 16 << 20


@dataclass(frozen=True)
class PointFile:
    """A design point TOML: the point, its raw ``[rtl]`` table (empty when absent; checked
    when it states a ``package``) and the path it was read from."""

    path: str
    point: DesignPoint
    rtl: dict[str, Any] = field(default_factory=dict)

    @property
    def lanes(self) -> int | None:
        """``[rtl] lanes`` if the file states it."""
        v = self.rtl.get("lanes")
        return v if isinstance(v, int) and not isinstance(v, bool) else None

    def package_on(self, device: str) -> str | None:
        """``[rtl] package`` when the page's ``device`` is the point's (``[rtl] device``,
        default ecp5-85): the package the I/O budget judges; ``None``: the device's
        default package."""
        from rvsm.rtl.fpga.build_budget import DEFAULT_DEVICE

        v = self.rtl.get("package")
        own = self.rtl.get("device", DEFAULT_DEVICE)
        return v if isinstance(v, str) and v and device == own else None


def read_result_text(path: str | os.PathLike, what: str) -> str:
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"{p}: no such {what} file")
    if p.stat().st_size > MAX_RESULT_BYTES:
        raise RvsmError(f"{p}: too large for a {what} ({p.stat().st_size} bytes)")
    return read_utf8_text(p, what)


def load_point_file(path: str | os.PathLike) -> PointFile:
    """The design point of ``path`` and its ``[rtl]`` table (read raw with tomllib)."""
    from rvsm.model.fixed.point_toml import from_toml_dict

    text = read_result_text(path, "design point")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RvsmError(f"{path}: not valid TOML: {exc}") from None
    rtl = data.pop("rtl", {})
    if not isinstance(rtl, dict):
        raise RvsmError(f"{path}: [rtl] must be a table")
    lanes = rtl.get("lanes")
    if lanes is not None and (isinstance(lanes, bool) or not isinstance(lanes, int)
                              or lanes < 1):
        raise RvsmError(f"{path}: rtl.lanes must be an integer >= 1, got {lanes!r}")
    if "package" in rtl:  # the I/O budget judges it: checked as rvsm config check does
        from rvsm.model.fixed.build_settings import BuildSettings
        from rvsm.rtl.fpga.build_settings import check_build_settings

        check_build_settings(BuildSettings.from_table(rtl, str(path)), str(path))
    return PointFile(str(path), from_toml_dict(data, str(path)), dict(rtl))


def read_json_object(path: str | os.PathLike, what: str, hint: str) -> dict[str, Any]:
    """The JSON object in ``path`` (``what`` names it in errors, ``hint`` says how to
    make it)."""
    text = read_result_text(path, what)
    try:
        data = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise RvsmError(f"{path}: not valid JSON ({exc}); {hint}") from None
    if not isinstance(data, dict):
        raise RvsmError(f"{path}: a {what} must be a JSON object; {hint}")
    return data


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def load_fpga_report(path: str | os.PathLike) -> dict[str, Any]:
    """An ``rvsm fpga --json`` report: ``lut4``, ``ff``, ``bram`` (each ``used`` and
    ``available``), ``fmax_mhz`` (None after synthesis only), ``lanes``, ``height``,
    ``width``, ``device``, ``mode``."""
    hint = "make it with rvsm fpga POINT --json > FILE.json"
    d = read_json_object(path, "rvsm fpga result", hint)
    for key in ("lut4", "ff", "bram"):
        u = d.get(key)
        if not (isinstance(u, dict) and _number(u.get("used")) and _number(u.get("available"))):
            raise RvsmError(f"{path}: {key} must hold used and available counts; {hint}")
    for key in ("lanes", "height", "width"):
        if not (isinstance(d.get(key), int) and d[key] >= 1):
            raise RvsmError(f"{path}: {key} must be an integer >= 1; {hint}")
    if d.get("fmax_mhz") is not None and not (_number(d["fmax_mhz"]) and d["fmax_mhz"] > 0):
        raise RvsmError(f"{path}: fmax_mhz must be a number > 0 or null; {hint}")
    if not isinstance(d.get("device"), str):
        raise RvsmError(f"{path}: device must name the part; {hint}")
    return d


def load_verify_result(path: str | os.PathLike) -> dict[str, Any]:
    """An ``rvsm verify --json`` result: at least ``compared`` and ``mismatches``."""
    hint = "make it with rvsm verify ... --json > FILE.json"
    d = read_json_object(path, "rvsm verify result", hint)
    for key in ("compared", "mismatches"):
        if not (isinstance(d.get(key), int) and not isinstance(d[key], bool) and d[key] >= 0):
            raise RvsmError(f"{path}: {key} must be an integer >= 0; {hint}")
    return d


@dataclass(frozen=True)
class RegressSummary:
    """A JUnit file's test cases: ``(suite, name, status)`` with status ``pass``,
    ``fail``, ``error`` or ``skipped``."""

    suites: tuple[str, ...]
    cases: tuple[tuple[str, str, str], ...]

    def count(self, status: str) -> int:
        """Cases with ``status``."""
        return sum(1 for c in self.cases if c[2] == status)


@dataclass(frozen=True)
class DatasheetInputs:
    """Everything the page shows: the point file, ``device`` budget, camera ``rate_hz``,
    ``lanes`` (None: the point's ``[rtl] lanes``, else the fewest that fit), state memory
    ``organisation``, the quality study (and ``picture``: ``(scene, step, images)`` or
    None) and the optional saved results with their paths; ``lane_cost``: a
    :class:`~rvsm.rtl.fpga.lane_cost.LaneCost` record (None: not synthesised);
    ``command``: the command line that made the page; ``quality_path``: the saved
    quality result (None: run by the page's command); ``commands``: per saved result
    (``fpga``, ``quality``, ``verify``, ``formal``, ``mutate``, ``regress``) the
    command that made it and where that command comes from, for results that do not
    record theirs (``--commands FILE.toml``); ``docs``: the path from the page to the
    project's ``docs/`` folder (for links); ``board``: a saved ``rvsm fpga --board
    --json`` report (:func:`~rvsm.sim.studies.datasheet_board.load_board_report`) and
    ``board_path`` its file."""

    point_file: PointFile
    device: DeviceBudget
    rate_hz: float
    quality: PointQuality
    quality_source: str
    lanes: int | None = None
    organisation: str = "rtl"
    fifo_depth: int = 16
    picture: tuple[str, int, dict[str, np.ndarray]] | None = None
    fpga: dict[str, Any] | None = None
    fpga_path: str | None = None
    lane_cost: dict[str, Any] | None = None
    verify: dict[str, Any] | None = None
    verify_path: str | None = None
    regress: RegressSummary | None = None
    regress_path: str | None = None
    formal: dict[str, Any] | None = None
    formal_path: str | None = None
    mutate: dict[str, Any] | None = None
    mutate_path: str | None = None
    command: str = "rvsm datasheet"
    quality_path: str | None = None
    commands: dict[str, tuple[str, str]] = field(default_factory=dict)
    docs: str = "../docs"
    board: dict[str, Any] | None = None
    board_path: str | None = None


def load_formal_report(path: str | os.PathLike) -> dict[str, Any]:
    """An ``rvsm formal --json`` report: ``checks`` (each ``check``, ``mode``, ``depth``,
    ``status``), ``size`` and ``model``."""
    hint = "make it with rvsm formal POINT --size HxW --json > FILE.json"
    d = read_json_object(path, "rvsm formal report", hint)
    checks = d.get("checks")
    if not isinstance(checks, list) or not all(
            isinstance(c, dict) and {"check", "status"} <= set(c) for c in checks) \
            or not isinstance(d.get("size"), list):
        raise RvsmError(f"{path}: not an rvsm formal report (no checks and size); {hint}")
    return d


def load_mutate_report(path: str | os.PathLike) -> dict[str, Any]:
    """An ``rvsm mutate --json`` report: ``mutations``, ``killed``, ``survivors``,
    ``checks``."""
    hint = "make it with rvsm mutate POINT --json > FILE.json"
    d = read_json_object(path, "rvsm mutate report", hint)
    if not all(_number(d.get(k)) for k in ("mutations", "killed")) \
            or not isinstance(d.get("survivors"), list):
        raise RvsmError(f"{path}: not an rvsm mutate report (no mutations, killed and "
                        f"survivors); {hint}")
    return d


def load_regress(path: str | os.PathLike) -> RegressSummary:
    """The runs of a regression: its results database (SQLite, ``rvsm regress -o``) or
    its JUnit XML (``--junit``)."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"{p}: no such regression result file")
    with open(p, "rb") as handle:
        sqlite = handle.read(16) == b"SQLite format 3\x00"
    return load_regress_database(p) if sqlite else load_regress_junit(p)


def load_regress_database(path: str | os.PathLike) -> RegressSummary:
    """The runs of an ``rvsm regress`` results database, opened read-only."""
    import sqlite3

    hint = "give the database rvsm regress PLAN.toml -o RESULTS.sqlite wrote"
    try:
        db = sqlite3.connect(f"{Path(path).resolve().as_uri()}?mode=ro", uri=True)
        try:
            kind = db.execute("SELECT value FROM meta WHERE key='kind'").fetchone()
            if kind is None or kind[0] != "rvsm regression":
                raise RvsmError(f"{path}: not a regression database; {hint}")
            rows = db.execute("SELECT plan, label, status FROM runs ORDER BY plan, label"
                              ).fetchall()
        finally:
            db.close()
    except sqlite3.Error as exc:
        raise RvsmError(f"{path}: cannot read the regression database ({exc}); {hint}") \
            from None
    plans = tuple(dict.fromkeys(str(r[0]) for r in rows))
    return RegressSummary(plans, tuple((str(a), str(b), str(c)) for a, b, c in rows))


def load_regress_junit(path: str | os.PathLike) -> RegressSummary:
    """The test cases of a JUnit XML file (``rvsm regress --junit``)."""
    hint = "make it with rvsm regress PLAN.toml --junit FILE.xml"
    text = read_result_text(path, "JUnit XML")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise RvsmError(f"{path}: not valid XML ({exc}); {hint}") from None
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    if root.tag not in ("testsuite", "testsuites") or not suites:
        raise RvsmError(f"{path}: no JUnit testsuite; {hint}")
    cases = []
    for s in suites:
        for c in s.iter("testcase"):
            status = ("fail" if c.find("failure") is not None else
                      "error" if c.find("error") is not None else
                      "skipped" if c.find("skipped") is not None else "pass")
            cases.append((s.get("name", ""), c.get("name", ""), status))
    return RegressSummary(tuple(s.get("name", "") for s in suites), tuple(cases))


#: The saved results a ``--commands`` file may give the command of.
COMMAND_KEYS = ("fpga", "board", "quality", "verify", "formal", "mutate", "regress")


def load_commands(path: str | os.PathLike) -> dict[str, tuple[str, str]]:
    """A ``--commands`` TOML file: for a saved result that does not record its own
    command line, ``[verify] command = "rvsm verify ..."`` (whole, no "...") and
    ``source = "..."`` (where the command comes from: the docs that quote it)."""
    text = read_result_text(path, "commands")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RvsmError(f"{path}: not valid TOML: {exc}") from None
    out = {}
    for key, table in data.items():
        if key not in COMMAND_KEYS or not isinstance(table, dict):
            raise RvsmError(f"{path}: unknown table [{key}]; valid tables: "
                            f"{', '.join(COMMAND_KEYS)}")
        cmd, source = table.get("command"), table.get("source")
        if not isinstance(cmd, str) or not cmd.startswith("rvsm ") or "..." in cmd:
            raise RvsmError(f"{path}: [{key}] command must be a whole rvsm command line "
                            "(no \"...\")")
        if not isinstance(source, str) or not source.strip():
            raise RvsmError(f"{path}: [{key}] source must say where the command comes from")
        out[key] = (cmd, source)
    return out
