"""Derive rtl/fpga/packages/lfe5u-85f-<package>.json from Project Trellis' iodb.json.

Usage (the database is not part of this project; fetch github:YosysHQ/prjtrellis-db):

    git -C <prjtrellis-db> show HEAD:ECP5/LFE5U-85F/iodb.json > iodb.json
    python scripts/derive_package_pins.py iodb.json <commit> rtl/fpga/packages

Each output file lists one package's bonded PIOs as rows ``[ball, bank, pio, function]``:
``pio`` is the Trellis/nextpnr site name (``P`` + side ``L``/``R``/``T``/``B`` + row (left,
right) or column (top, bottom) + PIO letter ``A``-``D``), ``function`` the pin's dual
function from the database ("" if none), e.g. ``PCLKT2_0`` or ``GR_PCLK2_1``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

PACKAGES = ("CABGA381", "CABGA554", "CABGA756")


def _side(row: int, col: int, max_row: int, max_col: int) -> str:
    if col == 0:
        return "L"
    if col == max_col:
        return "R"
    if row == 0:
        return "T"
    if row == max_row:
        return "B"
    raise ValueError(f"PIO at row {row}, col {col} is on no edge")


def derive(iodb: dict, package: str, commit: str) -> dict:
    """One package's pin table (see the module docstring)."""
    meta = {(m["row"], m["col"], m["pio"]): m for m in iodb["pio_metadata"]}
    max_row = max(r for r, _, _ in meta)
    max_col = max(c for _, c, _ in meta)
    rows = []
    for ball, p in iodb["packages"][package].items():
        m = meta[(p["row"], p["col"], p["pio"])]
        side = _side(p["row"], p["col"], max_row, max_col)
        index = p["row"] if side in "LR" else p["col"]
        rows.append([ball, m["bank"], f"P{side}{index}{p['pio']}", m.get("function", "")])
    rows.sort(key=lambda r: (r[1], r[2][1], int(r[2][2:-1]), r[2][-1]))
    return {
        "device": "LFE5U-85F",
        "package": package,
        "source": "Project Trellis database, github.com/YosysHQ/prjtrellis-db, "
                  "ECP5/LFE5U-85F/iodb.json (identical for LFE5UM-85F and LFE5UM5G-85F)",
        "commit": commit,
        "columns": ["ball", "bank", "pio", "function"],
        "pins": rows,
    }


def main(argv: list[str]) -> int:
    iodb_path, commit, out = argv
    iodb = json.loads(Path(iodb_path).read_text())
    for package in PACKAGES:
        table = derive(iodb, package, commit)
        lines = ",\n".join("  " + json.dumps(r) for r in table.pop("pins"))
        head = json.dumps(table, indent=1)[:-2]
        text = f'{head},\n "pins": [\n{lines}\n ]\n}}\n'
        json.loads(text)
        (Path(out) / f"lfe5u-85f-{package.lower()}.json").write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
