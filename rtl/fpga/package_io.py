"""The I/O of each device's packages: pins per bank, differential pairs, true-LVDS output
pairs, gearing and SerDes; the budget-level summary a design search checks links against.

**ECP5** (:data:`ECP5_BANKS`, the one place the per-bank counts live): per die and package,
per bank, the user I/O pins bonded out, the differential pairs (PIOA/PIOB and PIOC/PIOD
with both pins bonded) and the true-LVDS output pairs (an A/B pair on a left or right
bank). Counted from Project Trellis' database (``prjtrellis-db``, commit
:data:`TRELLIS_DB_COMMIT`, ``ECP5/<die>/iodb.json``: each package's pins and each PIO's
bank); the totals are the data sheet's user I/O (205 on the LFE5U-85F CABGA381, 259 on
the CABGA554, 365 on the CABGA756). Banks 2, 3 (right) and 6, 7 (left) have edge clocks,
so the X2 and 7:1 gearing; 0, 1 (top), 4 and 8 (bottom) serve X1 and single-ended I/O.
On the LFE5U-85F the counts are derived from the pin planner's own tables
(:mod:`rvsm.rtl.fpga.package_pins`, the same prjtrellis-db commit), so the budget and the
planner count the same pins; the 25k and 45k dies have no pin table here and keep the
counts read from the same database.

**Other families**: their packages' user I/O where known, no per-bank table and no gearing
model: :attr:`PackageIo.estimate_only`, so the I/O budget is unknown there, not a verdict.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.package_pins import PACKAGES as PIN_TABLE_PACKAGES
from rvsm.rtl.fpga.package_pins import TRELLIS_DB_COMMIT, load_package

__all__ = ["ECP5_BANKS", "ECP5_GEARINGS", "TRELLIS_DB_COMMIT", "BankIo", "Gearing",
           "PackageIo", "ecp5_packages", "estimate_only"]

TRELLIS_SOURCE = (f"counted from Project Trellis prjtrellis-db {TRELLIS_DB_COMMIT[:7]} "
                  "ECP5/{die}/iodb.json (pins per package, bank per PIO; A/B and C/D "
                  "pairs with both pins bonded; true LVDS on A/B pairs of banks 2, 3, 6, 7)")
SYSIO_SOURCE = ("Lattice TN1262 / FPGA-TN-02032 ECP5 and ECP5-5G sysIO Usage Guide, "
                "'sysIO Buffer Overview': PIOA/PIOB and PIOC/PIOD make the differential "
                "pairs, one true LVDS driver per A/B pair; left and right sides only: "
                "unconfirmed (table not found), taken from the issue's notes")

#: Side of each ECP5 bank.
ECP5_SIDES = {0: "top", 1: "top", 2: "right", 3: "right", 4: "bottom", 6: "left",
              7: "left", 8: "bottom"}
#: ECP5 banks with edge clocks (ECLKSYNCB): the X2 and 7:1 gearing.
ECP5_EDGE_BANKS = frozenset({2, 3, 6, 7})


@dataclass(frozen=True)
class BankIo:
    """One I/O bank of a package: ``pins`` user I/O, ``pairs`` differential pairs,
    ``lvds_out_pairs`` of them with a true LVDS output driver, ``edge_clock``: the bank
    has edge clocks (the high-speed gearing)."""

    bank: int
    side: str
    pins: int
    pairs: int
    lvds_out_pairs: int
    edge_clock: bool


@dataclass(frozen=True)
class Gearing:
    """A serialiser/deserialiser ratio of the I/O cells: ``name``, the ``primitives``,
    ``max_mbps_per_pair`` (None: unconfirmed) and ``edge_banks`` (needs edge clocks)."""

    name: str
    primitives: str
    max_mbps_per_pair: float | None
    edge_banks: bool
    source: str


#: ECP5 gearing. X2: IDDRX2F/ODDRX2F take 4 bits a pair per CLKDIVF system clock at half
#: the edge clock; the edge clock reaches 400 MHz, 800 Mbit/s per pair.
ECP5_GEARINGS = (
    Gearing("x2", "IDDRX2F/ODDRX2F (ECLKSYNCB, CLKDIVF)", 800.0, True,
            "Lattice FPGA-TN-02035 ECP5 and ECP5-5G High-Speed I/O Interface, section "
            "5.13.2.2 Receive Aligned Interface: GDDRX2_RX.ECLK at its max speed of 400 MHz "
            "(UI = 1.25 ns), 800 Mbit/s per pair; the fMAX table of FPGA-DS-02012 "
            "(External Switching Characteristics): table number unconfirmed"),
    Gearing("7:1", "IDDR71B/ODDR71B (ECLKSYNCB, CLKDIVF)", None, True,
            "Lattice FPGA-TN-02035 and RD1093 (7:1 LVDS video interface): the largest rate "
            "per pair unconfirmed"),
    Gearing("x1", "IDDRX1F/ODDRX1F", None, False,
            "Lattice FPGA-TN-02035 (generic DDR X1): the largest rate per pin unconfirmed"),
)

#: Per ECP5 die and package, per bank: (pins, pairs, true-LVDS output pairs); see the
#: module docstring for where they come from.
ECP5_BANKS: dict[tuple[str, str], dict[int, tuple[int, int, int]]] = {
    ("LFE5U-25F", "CABGA256"): {0: (24, 12, 0), 1: (32, 16, 0), 2: (32, 16, 8),
                                3: (32, 16, 8), 6: (32, 16, 8), 7: (32, 16, 8),
                                8: (13, 6, 0)},
    ("LFE5U-25F", "CABGA381"): {0: (24, 12, 0), 1: (32, 16, 0), 2: (32, 16, 8),
                                3: (32, 16, 8), 6: (32, 16, 8), 7: (32, 16, 8),
                                8: (13, 6, 0)},
    ("LFE5U-45F", "CABGA381"): {0: (27, 13, 0), 1: (33, 16, 0), 2: (32, 16, 8),
                                3: (33, 16, 8), 6: (33, 16, 8), 7: (32, 16, 8),
                                8: (13, 6, 0)},
    ("LFE5U-45F", "CABGA554"): {0: (32, 16, 0), 1: (40, 20, 0), 2: (32, 16, 8),
                                3: (48, 24, 12), 6: (48, 24, 12), 7: (32, 16, 8),
                                8: (13, 6, 0)},
}


def _from_pin_table(package: str) -> dict[int, tuple[int, int, int]]:
    """Per bank ``(pins, pairs, true-LVDS output pairs)`` of the LFE5U-85F in ``package``,
    counted from the pin planner's table (:mod:`rvsm.rtl.fpga.package_pins`)."""
    return {b: (r["pins"], r["pairs"], r["lvds_output"])
            for b, r in load_package(package).bank_summary().items()}


#: The ECP5-85 packages: derived from the pin tables the pin planner places with, so the
#: I/O budget and the planner count the same pins.
ECP5_BANKS.update({("LFE5U-85F", pk): _from_pin_table(pk) for pk in PIN_TABLE_PACKAGES})
#: The LFE5UM5G-85F (ECP5-5G) has the LFE5U-85F's pins in each package (the same
#: iodb.json counts) and two DCUs of two SerDes channels at up to 5 Gbit/s.
ECP5_5G_SERDES = (4, 5.0, "Lattice FPGA-DS-02012 ECP5 and ECP5-5G Family Data Sheet, "
                          "SERDES and PCS (2 DCUs x 2 channels on the 45k/85k dies): "
                          "table number unconfirmed")


@dataclass(frozen=True)
class PackageIo:
    """The I/O one package of a part offers (module docstring). ``part`` the die or
    variant, ``user_io`` pins (None: unknown), ``banks`` (empty: no per-bank figures),
    ``gearings``, ``serdes_channels`` at ``serdes_gbps``, ``source`` of the figures;
    ``estimate_only``: no per-bank, gearing or SerDes model (its 0 SerDes channels mean
    "not modelled"), so no I/O verdict."""

    part: str
    package: str
    user_io: int | None
    banks: tuple[BankIo, ...]
    gearings: tuple[Gearing, ...]
    serdes_channels: int
    serdes_gbps: float
    source: str
    estimate_only: bool = False

    @property
    def name(self) -> str:
        """``"LFE5U-85F CABGA381"``."""
        return f"{self.part} {self.package}"

    @property
    def pairs(self) -> int:
        """Differential pairs in all banks."""
        return sum(b.pairs for b in self.banks)

    @property
    def lvds_out_pairs(self) -> int:
        """True-LVDS output pairs in all banks."""
        return sum(b.lvds_out_pairs for b in self.banks)

    def gearing(self, name: str) -> Gearing:
        """The :class:`Gearing` called ``name``; :class:`RvsmError` naming the choices."""
        for g in self.gearings:
            if g.name == name:
                return g
        raise RvsmError(f"{self.name} has no gearing {name!r}; choose one of: "
                        f"{', '.join(g.name for g in self.gearings) or 'none known'}")

    def summary(self) -> str:
        """One line: pins, pairs, true-LVDS pairs, gearing and SerDes."""
        if self.estimate_only:
            pins = "?" if self.user_io is None else str(self.user_io)
            return f"{self.name}: {pins} user I/O (estimate only: {self.source})"
        edge = [b for b in self.banks if b.edge_clock]
        gear = ", ".join(f"{g.name} {_mbps(g.max_mbps_per_pair)}" for g in self.gearings)
        return (f"{self.name}: {self.user_io} user I/O, {self.pairs} pairs "
                f"({sum(b.pairs for b in edge)} on edge-clock banks "
                f"{', '.join(str(b.bank) for b in edge)}), {self.lvds_out_pairs} true-LVDS "
                f"output pairs; gearing {gear}; SerDes {self.serdes_channels}"
                + (f" x {self.serdes_gbps:g} Gbit/s" if self.serdes_channels else ""))

    def to_dict(self) -> dict:
        """JSON-ready figures, per bank."""
        return {"part": self.part, "package": self.package, "user_io": self.user_io,
                "pairs": self.pairs, "lvds_out_pairs": self.lvds_out_pairs,
                "banks": [asdict(b) for b in self.banks],
                "gearings": [{"name": g.name, "primitives": g.primitives,
                              "max_mbps_per_pair": g.max_mbps_per_pair,
                              "edge_banks": g.edge_banks, "source": g.source}
                             for g in self.gearings],
                "serdes_channels": self.serdes_channels, "serdes_gbps": self.serdes_gbps,
                "estimate_only": self.estimate_only, "source": self.source}


def _mbps(v: float | None) -> str:
    return "? Mbit/s (unconfirmed)" if v is None else f"{v:g} Mbit/s"


def _ecp5(die: str, package: str, serdes: tuple[int, float, str] | None = None,
          part: str | None = None) -> PackageIo:
    banks = tuple(BankIo(b, ECP5_SIDES[b], pins, pairs, lvds, b in ECP5_EDGE_BANKS)
                  for b, (pins, pairs, lvds) in sorted(ECP5_BANKS[(die, package)].items()))
    n, gbps, ssrc = serdes or (0, 0.0, "LFE5U parts have no SerDes")
    return PackageIo(part or die, package, sum(b.pins for b in banks), banks, ECP5_GEARINGS,
                     n, gbps, f"{TRELLIS_SOURCE.format(die=die)}; {SYSIO_SOURCE}; {ssrc}")


def ecp5_packages(die: str) -> tuple[PackageIo, ...]:
    """Every package of ``die`` in :data:`ECP5_BANKS`, the CABGA381 first; on the 85k die
    also the LFE5UM5G-85F (same pins, 4 x 5 Gbit/s SerDes)."""
    mine = sorted((p for d, p in ECP5_BANKS if d == die), key=lambda p: p != "CABGA381")
    out = [_ecp5(die, p) for p in mine]
    if die == "LFE5U-85F":
        out += [_ecp5(die, p, ECP5_5G_SERDES, "LFE5UM5G-85F") for p in mine]
    return tuple(out)


def estimate_only(part: str, package: str, user_io: int | None, source: str) -> PackageIo:
    """A package with only its user I/O (or none) known: no I/O verdict."""
    return PackageIo(part, package, user_io, (), (), 0, 0.0, source, estimate_only=True)
