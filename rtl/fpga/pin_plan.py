"""Pin planner: a board design's ports -> package sites, and the LPF nextpnr-ecp5 reads.

The ports (:class:`BoardPorts`) are source-synchronous LVDS links (:class:`LinkSpec`: a
receiver of ``data_pairs`` pairs with a forwarded clock input, or a transmitter of
``data_pairs`` pairs with a forwarded clock output), single-ended control pins and the
board oscillator. :func:`plan_pins` assigns every port a ball of an ECP5-85 package
(:mod:`rvsm.rtl.fpga.package_pins`) under these rules:

* Gearing (IDDRX2F/ODDRX2F) exists on the left and right sides only, so every link pair
  is on a left or right bank; transmit pairs (data and forwarded clock) on A/B pairs,
  the only ones with a true LVDS output driver (TN1262).
* A link is one edge clock (ECLKSYNCB) and one CLKDIVF. A side has two edge clocks,
  ECLK0 and ECLK1, and two CLKDIVFs, one per index (4 CLKDIVF on the die, nextpnr's
  ``CLKDIVF available 4``). nextpnr-ecp5 0.11 gives a link the first free ECLK index in
  each bank it touches, so (checked by placing small designs): one link alone on a side
  may span both banks of that side; two links on one side must share one bank (links in
  the two banks of a side both take ECLK0 and collide on that side's CLKDIVF 0).
* A receiver's forwarded clock goes to a dedicated clock input pair (``PCLKT``) in a
  bank of its link, which reaches the ECLKSYNCB directly.
* Single-ended pins (LVCMOS33) go on the top and bottom banks 0 and 1 (3.3 V banks), the
  oscillator on a ``PCLKT`` pin there.

nextpnr-ecp5's convention for a differential port: one top-level port on the true (A or
C) pin with ``IO_TYPE=LVDS``; the complement pin is implied. When nothing fits,
:class:`RvsmError` names the figures (pairs needed against pairs per side and bank).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from itertools import product

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.package_pins import PACKAGES, DiffPair, PackagePins, load_package

__all__ = ["SIDES", "BoardPorts", "LinkSpec", "PinPlan", "PinSite", "edge_clock_placements",
           "plan_pins", "plan_pins_in"]

#: Banks of each gearing side.
SIDES = {"L": (6, 7), "R": (2, 3)}
#: Banks for single-ended pins (3.3 V capable top and bottom banks, not the config bank 8).
SINGLE_ENDED_BANKS = (0, 1)


@dataclass(frozen=True)
class LinkSpec:
    """One source-synchronous LVDS link: ``name`` (port prefix), ``direction`` ``"rx"``
    or ``"tx"``, ``data_pairs`` (>= 1, framing lanes included), edge clock (MHz)."""

    name: str
    direction: str
    data_pairs: int
    eclk_mhz: float = 400.0

    def __post_init__(self) -> None:
        if self.direction not in ("rx", "tx"):
            raise RvsmError(f"link {self.name!r}: direction must be rx or tx")
        if self.data_pairs < 1:
            raise RvsmError(f"link {self.name!r}: needs at least one data pair")

    @property
    def clock_port(self) -> str:
        return f"{self.name}_clk"

    def data_port(self, i: int) -> str:
        return f"{self.name}_d{i}"

    @property
    def pairs(self) -> int:
        """Pairs including the forwarded clock."""
        return self.data_pairs + 1


@dataclass(frozen=True)
class BoardPorts:
    """Every port of a board top: ``links``, single-ended ``controls`` (port names) and
    the board ``oscillator`` (port name, frequency in MHz)."""

    links: tuple[LinkSpec, ...]
    controls: tuple[str, ...] = ()
    oscillator: str = "clk_osc"
    oscillator_mhz: float = 100.0


@dataclass(frozen=True)
class PinSite:
    """One port at one ball: ``io_type`` ``"LVDS"`` or ``"LVCMOS33"``; ``pair`` the
    ``PL11A/B`` name of a differential port's pair ("" for single-ended)."""

    port: str
    ball: str
    pio: str
    bank: int
    io_type: str
    pair: str = ""


@dataclass(frozen=True)
class PinPlan:
    """The sites of every port in ``package``; ``link_sides`` maps a link to its side
    and banks; ``rejected`` lists smaller packages tried first, with the reason;
    ``front_end``: the design the pins belong to (the board top's front end class)."""

    package: str
    sites: tuple[PinSite, ...]
    link_sides: dict[str, tuple[str, tuple[int, ...]]]
    frequencies: dict[str, float]
    rejected: tuple[tuple[str, str], ...] = field(default=())
    front_end: str = ""

    @property
    def pins_used(self) -> int:
        """Package pins taken: two per differential port, one per single-ended."""
        return sum(2 if s.io_type == "LVDS" else 1 for s in self.sites)

    @property
    def pins_available(self) -> int:
        return len(load_package(self.package).pins)

    def lpf(self) -> str:
        """The LPF: ``LOCATE COMP`` and ``IOBUF PORT`` for every port, ``FREQUENCY PORT``
        for the clocks."""
        lines = [f"# pin plan for LFE5U-85F {self.package} (rvsm.rtl.fpga.pin_plan)"]
        for s in self.sites:
            note = f"  # bank {s.bank} {s.pio}" + (f" pair {s.pair}" if s.pair else "")
            lines.append(f'LOCATE COMP "{s.port}" SITE "{s.ball}";{note}')
            lines.append(f'IOBUF PORT "{s.port}" IO_TYPE={s.io_type};')
        for port, mhz in self.frequencies.items():
            lines.append(f'FREQUENCY PORT "{port}" {mhz:g} MHZ;')
        return "\n".join(lines) + "\n"

    def to_dict(self) -> dict:
        return {"package": self.package, "front_end": self.front_end,
                "pins_used": self.pins_used,
                "pins_available": self.pins_available,
                "links": {k: {"side": s, "banks": list(b)} for k, (s, b) in
                          self.link_sides.items()},
                "rejected": [{"package": p, "reason": r} for p, r in self.rejected],
                "sites": [s.__dict__ for s in self.sites]}


def edge_clock_placements(links: Sequence[LinkSpec]
                          ) -> Iterator[dict[str, tuple[str, tuple[int, ...]]]]:
    """Every (side, banks) choice per link that the edge-clock rules allow, links alone
    on a side spanning both banks tried first."""
    choices = [(side, banks) for side, pair in SIDES.items()
               for banks in (pair, (pair[0],), (pair[1],))]
    for combo in product(choices, repeat=len(links)):
        per_side: dict[str, list[tuple[int, ...]]] = {}
        for side, banks in combo:
            per_side.setdefault(side, []).append(banks)
        ok = True
        for used in per_side.values():
            if len(used) > 2 or (len(used) == 2 and (len(used[0]) != 1 or used[0] != used[1])):
                ok = False
        if ok:
            yield {link.name: c for link, c in zip(links, combo, strict=True)}


def _assign(table: PackagePins, links: Sequence[LinkSpec],
            where: dict[str, tuple[str, tuple[int, ...]]]) -> dict[str, DiffPair] | None:
    """Pairs for every link port under placement ``where``, or None if short."""
    free = [p for p in table.pairs if p.gearing]
    out: dict[str, DiffPair] = {}

    def take(link: LinkSpec, want) -> DiffPair | None:
        banks = where[link.name][1]
        for pick in want:
            for p in free:
                if p.bank in banks and pick(p):
                    free.remove(p)
                    return p
        return None

    # transmitters first: they need A/B pairs; keep clock-input pairs for receivers
    for link in sorted(links, key=lambda k: k.direction != "tx"):
        ports = [link.clock_port] + [link.data_port(i) for i in range(link.data_pairs)]
        for k, port in enumerate(ports):
            if link.direction == "tx":
                want = [lambda p: p.lvds_output and not p.pclk, lambda p: p.lvds_output]
            elif k == 0:
                want = [lambda p: p.pclk and not p.lvds_output, lambda p: p.pclk]
            else:
                want = [lambda p: not p.lvds_output and not p.pclk,
                        lambda p: not p.pclk, lambda p: True]
            pair = take(link, want)
            if pair is None:
                return None
            out[port] = pair
    return out


def _shortfall(table: PackagePins, links: Sequence[LinkSpec]) -> str:
    rx = sum(k.pairs for k in links if k.direction == "rx")
    tx = sum(k.pairs for k in links if k.direction == "tx")
    s = table.bank_summary()
    sides = ", ".join(
        f"{'left' if side == 'L' else 'right'} banks {a}+{b}: "
        f"{s[a]['pairs']}+{s[b]['pairs']} pairs, "
        f"{s[a]['lvds_output']}+{s[b]['lvds_output']} true-LVDS output"
        for side, (a, b) in SIDES.items())
    biggest = max(k.pairs for k in links)
    return (f"{table.package}: {len(links)} links need {rx} receive pairs and {tx} transmit "
            f"(true-LVDS output) pairs with their forwarded clocks, the largest link "
            f"{biggest} pairs on one side; the package has {sides}; at most 2 links a "
            f"side (one spanning both banks, or two in one bank)")


def plan_pins_in(ports: BoardPorts, package: str) -> PinPlan:
    """The plan in ``package``; :class:`RvsmError` with the figures if it does not fit."""
    table = load_package(package)
    links = list(ports.links)
    if len({k.name for k in links}) != len(links):
        raise RvsmError("link names must be distinct")
    if len(links) > 4:
        raise RvsmError(f"{len(links)} links need {len(links)} edge clocks with a CLKDIVF "
                        "each; the ECP5 has 4 CLKDIVF (2 a side): merge links")
    assigned = where = None
    for where in edge_clock_placements(links):
        assigned = _assign(table, links, where)
        if assigned is not None:
            break
    if assigned is None:
        raise RvsmError(_shortfall(table, links))
    sites = []
    for link in links:
        for port in [link.clock_port] + [link.data_port(i) for i in range(link.data_pairs)]:
            p = assigned[port]
            sites.append(PinSite(port, p.p.ball, p.p.pio, p.bank, "LVDS", p.name))
    single = [p for p in table.pins if p.bank in SINGLE_ENDED_BANKS]
    clocks = [p for p in single if p.function.startswith("PCLKT")]
    if not clocks or len(single) < 1 + len(ports.controls):
        raise RvsmError(f"{table.package}: {1 + len(ports.controls)} single-ended pins "
                        f"needed on banks {SINGLE_ENDED_BANKS}, {len(single)} there")
    osc = clocks[0]
    sites.append(PinSite(ports.oscillator, osc.ball, osc.pio, osc.bank, "LVCMOS33"))
    rest = [p for p in single if p is not osc and not p.function.startswith("PCLK")]
    rest += [p for p in single if p is not osc and p.function.startswith("PCLK")]
    for name, p in zip(ports.controls, rest, strict=False):
        sites.append(PinSite(name, p.ball, p.pio, p.bank, "LVCMOS33"))
    freqs = {ports.oscillator: ports.oscillator_mhz}
    freqs.update({k.clock_port: k.eclk_mhz for k in links if k.direction == "rx"})
    return PinPlan(table.package, tuple(sites), dict(where), freqs)


def plan_pins(ports: BoardPorts, package: str | None = None) -> PinPlan:
    """Plan ``ports`` in ``package``, or (``None``) in the smallest ECP5-85 package that
    carries them (:data:`PACKAGES` in order); the plan's ``rejected`` says why each
    smaller package failed. :class:`RvsmError` if none does."""
    if package is not None:
        return plan_pins_in(ports, package)
    rejected = []
    for pkg in PACKAGES:
        try:
            plan = plan_pins_in(ports, pkg)
        except RvsmError as exc:
            rejected.append((pkg, str(exc)))
            continue
        return PinPlan(plan.package, plan.sites, plan.link_sides, plan.frequencies,
                       tuple(rejected))
    raise RvsmError("no ECP5-85 package carries these links: " + "; ".join(
        r for _, r in rejected) + "; pack the output or split the links")
