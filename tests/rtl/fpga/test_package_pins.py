"""Pin tables of the ECP5-85 packages (rtl/fpga/package_pins.py) against their data files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga import package_pins
from rvsm.rtl.fpga.package_pins import PACKAGES, TRELLIS_DB_COMMIT, load_package

#: User I/O per package (Lattice FPGA-DS-02012, ECP5 family data sheet, the package table).
USER_IO = {"CABGA381": 205, "CABGA554": 259, "CABGA756": 365}


def _rows(package: str) -> list[list]:
    path = Path(package_pins.__file__).parent / "packages" / f"lfe5u-85f-{package.lower()}.json"
    return json.loads(path.read_text())["pins"]


@pytest.mark.parametrize("package", PACKAGES)
def test_counts_match_a_plain_recount_of_the_rows(package):
    table = load_package(package)
    rows = _rows(package)
    assert len(table.pins) == len(rows) == USER_IO[package]
    assert table.commit == TRELLIS_DB_COMMIT and "prjtrellis-db" in table.source
    sites = {pio: (ball, bank) for ball, bank, pio, _ in rows}
    # the oracle: a pair is an A (or C) row whose B (or D) row is bonded too
    pairs = [pio for pio in sites if pio[-1] in "AC"
             and pio[:-1] + {"A": "B", "C": "D"}[pio[-1]] in sites]
    lvds = [pio for pio in pairs if pio[1] in "LR" and pio[-1] == "A"]
    assert table.totals()["pairs"] == len(pairs)
    assert table.totals()["lvds_output"] == len(lvds)
    assert table.totals()["gearing"] == sum(pio[1] in "LR" for pio in pairs)
    assert sum(r["pins"] for r in table.bank_summary().values()) == len(rows)
    for pair in table.pairs:
        assert pair.p.bank == pair.n.bank and pair.p.side == pair.n.side
        assert pair.lvds_output == (pair.side in "LR" and pair.p.letter == "A")
    # true LVDS output pairs only on the left and right banks (2, 3, 6, 7)
    assert {p.bank for p in table.pairs if p.lvds_output} <= {2, 3, 6, 7}


def test_cabga381_figures():
    t = load_package("CABGA381")
    assert t.totals() == {"pins": 205, "pairs": 100, "lvds_output": 33, "gearing": 65,
                          "pclk": 12}
    assert [t.bank_summary()[b]["lvds_output"] for b in (2, 3, 6, 7)] == [9, 8, 8, 8]
    j20 = t.by_ball["J20"]
    assert (j20.bank, j20.function, j20.is_true) == (2, "PCLKT2_0", True)
    # every bank with gearing has two dedicated clock input pairs
    assert all(t.bank_summary()[b]["pclk"] == 2 for b in (2, 3, 6, 7))


@pytest.mark.parametrize("package, totals, left, right", [
    ("CABGA381", (100, 33, 65), (16, 16, 8, 8), (17, 16, 9, 8)),
    ("CABGA554", (129, 40, 80), (24, 16, 12, 8), (16, 24, 8, 12)),
    ("CABGA756", (182, 56, 112), (32, 24, 16, 12), (24, 32, 12, 16)),
])
def test_pairs_per_package_and_side(package, totals, left, right):
    """The figures docs/fpga.md "Board build" quotes: pairs, true-LVDS output pairs and
    gearing pairs in all; pairs of banks 6, 7 (left) and 2, 3 (right), then their
    true-LVDS output pairs."""
    t = load_package(package)
    tot, s = t.totals(), t.bank_summary()
    assert (tot["pairs"], tot["lvds_output"], tot["gearing"]) == totals
    for banks, want in (((6, 7), left), ((2, 3), right)):
        got = tuple(s[b]["pairs"] for b in banks) + tuple(s[b]["lvds_output"] for b in banks)
        assert got == want


def test_unknown_package_is_refused():
    with pytest.raises(RvsmError, match="no pin table"):
        load_package("CSFBGA285")
