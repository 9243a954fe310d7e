"""The bonded pins of the ECP5-85 packages: ball, bank, PIO site, pair, LVDS and clock roles.

Data: ``rtl/fpga/packages/lfe5u-85f-<package>.json``, derived by
``scripts/derive_package_pins.py`` from Project Trellis' database
(github.com/YosysHQ/prjtrellis-db, ``ECP5/LFE5U-85F/iodb.json`` at commit
:data:`TRELLIS_DB_COMMIT`; the file is identical for LFE5UM-85F and LFE5UM5G-85F). One row
per bonded PIO: ball name, I/O bank, Trellis/nextpnr site name (``PL11A``: side ``L``, row
11, PIO ``A``) and the pin's dual function (``PCLKT2_0``, ``GR_PCLK2_1``, ...).

Rules applied on top of the data (Lattice TN1262 "ECP5 and ECP5-5G sysIO Usage Guide",
sysIO buffer overview; nextpnr-ecp5 ``ecp5/pack.cc``):

* PIOs A/B and C/D of one site form a differential pair; A (C) is the true (``P``) side.
* One true LVDS output driver per A/B pair: :attr:`DiffPair.lvds_output` needs an A/B pair
  on the left or right side (banks 2, 3, 6, 7).
* Only the left and right sides have the full IOLOGIC (IDDRX2F/ODDRX2F, 7:1 gearing, edge
  clocks); top and bottom have SIOLOGIC (plain registers and X1 DDR only): nextpnr refuses
  any other mode there. :attr:`DiffPair.gearing`.
* ``PCLKT<bank>_<n>`` / ``PCLKC<bank>_<n>`` are the dedicated primary clock inputs (true
  and complement): :attr:`DiffPair.pclk`; ``GR_PCLK`` pins reach the clock tree through
  general routing.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path

from rvsm.model.infra.errors import RvsmError

__all__ = [
    "PACKAGES",
    "TRELLIS_DB_COMMIT",
    "DiffPair",
    "PackagePin",
    "PackagePins",
    "load_package",
]

#: prjtrellis-db commit the pin tables were derived from.
TRELLIS_DB_COMMIT = "4dda149b9e4f1753ebc8b011ece2fe794be1281a"
#: ECP5-85 packages with a pin table, smallest first.
PACKAGES = ("CABGA381", "CABGA554", "CABGA756")
_DATA = Path(__file__).parent / "packages"
_PARTNER = {"A": "B", "B": "A", "C": "D", "D": "C"}


@dataclass(frozen=True)
class PackagePin:
    """One bonded PIO: ``ball`` (e.g. ``"J20"``), I/O ``bank``, Trellis site ``pio``
    (e.g. ``"PR50A"``) and its dual ``function`` ("" if none)."""

    ball: str
    bank: int
    pio: str
    function: str

    @property
    def side(self) -> str:
        """``"L"``, ``"R"``, ``"T"`` or ``"B"`` (left, right, top, bottom)."""
        return self.pio[1]

    @property
    def letter(self) -> str:
        """PIO letter in its site, ``"A"`` .. ``"D"``."""
        return self.pio[-1]

    @property
    def is_true(self) -> bool:
        """The true (``P``) side of a pair: PIO A or C."""
        return self.letter in "AC"

    @property
    def partner_pio(self) -> str:
        """Site name of the other pin of this pin's pair."""
        return self.pio[:-1] + _PARTNER[self.letter]


@dataclass(frozen=True)
class DiffPair:
    """A bonded differential pair: its true pin ``p`` and complement ``n``."""

    p: PackagePin
    n: PackagePin

    @property
    def bank(self) -> int:
        return self.p.bank

    @property
    def side(self) -> str:
        return self.p.side

    @property
    def gearing(self) -> bool:
        """Left or right side: IDDRX2F/ODDRX2F and 7:1 gearing on edge clocks."""
        return self.side in "LR"

    @property
    def lvds_output(self) -> bool:
        """Has a true LVDS output driver (an A/B pair on the left or right side)."""
        return self.gearing and self.p.letter == "A"

    @property
    def pclk(self) -> bool:
        """A dedicated primary clock input pair (``PCLKT``/``PCLKC``)."""
        return self.p.function.startswith("PCLKT")

    @property
    def name(self) -> str:
        """``"PR50A/B"`` style."""
        return f"{self.p.pio}/{self.n.letter}"


@dataclass(frozen=True)
class PackagePins:
    """The bonded pins of one package of the ECP5-85 and the pairs they form."""

    device: str
    package: str
    source: str
    commit: str
    pins: tuple[PackagePin, ...]

    @cached_property
    def by_pio(self) -> dict[str, PackagePin]:
        return {p.pio: p for p in self.pins}

    @cached_property
    def by_ball(self) -> dict[str, PackagePin]:
        return {p.ball: p for p in self.pins}

    @cached_property
    def pairs(self) -> tuple[DiffPair, ...]:
        """Every pair with both pins bonded, in table order (bank, side, index)."""
        return tuple(DiffPair(p, self.by_pio[p.partner_pio]) for p in self.pins
                     if p.is_true and p.partner_pio in self.by_pio)

    @property
    def banks(self) -> tuple[int, ...]:
        return tuple(sorted({p.bank for p in self.pins}))

    def bank_summary(self) -> dict[int, dict[str, int]]:
        """Per bank: ``pins`` bonded, differential ``pairs``, ``lvds_output`` pairs,
        ``gearing`` pairs (X2/7:1 capable) and ``pclk`` pairs."""
        pins = Counter(p.bank for p in self.pins)
        out = {b: {"pins": pins[b], "pairs": 0, "lvds_output": 0, "gearing": 0, "pclk": 0}
               for b in self.banks}
        for pair in self.pairs:
            row = out[pair.bank]
            row["pairs"] += 1
            row["lvds_output"] += pair.lvds_output
            row["gearing"] += pair.gearing
            row["pclk"] += pair.pclk
        return out

    def totals(self) -> dict[str, int]:
        """:meth:`bank_summary` summed over the banks."""
        keys = ("pins", "pairs", "lvds_output", "gearing", "pclk")
        rows = self.bank_summary().values()
        return {k: sum(r[k] for r in rows) for k in keys}


@cache
def load_package(package: str = "CABGA381") -> PackagePins:
    """The pin table of ``package`` (one of :data:`PACKAGES`) of the LFE5U-85F."""
    key = package.upper()
    if key not in PACKAGES:
        raise RvsmError(f"no pin table for package {package!r}; known: {', '.join(PACKAGES)}")
    data = json.loads((_DATA / f"lfe5u-85f-{key.lower()}.json").read_text())
    if data["columns"] != ["ball", "bank", "pio", "function"]:
        raise RvsmError(f"pin table of {key} has unexpected columns {data['columns']}")
    pins = tuple(PackagePin(ball, int(bank), pio, fn) for ball, bank, pio, fn in data["pins"])
    return PackagePins(data["device"], data["package"], data["source"], data["commit"], pins)
