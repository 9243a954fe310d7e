"""Pixels in and spikes out over a package's pins: lanes, words and bank placement.

Pure arithmetic, shared by the feasibility check, a board front end and a pin planner.
A camera of ``H x W`` pixels at ``rate`` steps/s with ``N``-bit ADC codes and ``S`` scales
carries

* **in**: ``H * W * rate * N`` bits/s of ADC codes (28 Gbit/s at 250x400, 40 kHz, N = 7);
* **out**: ``H * W * rate * S * 2`` bits/s, a bit per scale and sign per pixel (16 Gbit/s
  at dog2), the positions implied by the framing (raster order from a frame start).

A pair geared ``g`` (:class:`~rvsm.rtl.fpga.package_io.Gearing`) carries at most
``g.max_mbps_per_pair``; at a core clock ``f`` it moves ``b = floor(max / f)`` bits per
core cycle (ECP5 X2 at 100 MHz: 4 bits per 200 MHz CLKDIVF cycle from a 400 MHz edge
clock, 8 bits per core cycle), so a direction needs ``ceil(ceil(bits_per_s / f) / b)``
data pairs (35 in, 20 out); a core clock above the pair's rate: ``b = 0`` and
``ceil(bits_per_s / max)`` pairs. Each direction is **one link**, as the board front end
builds it (:mod:`rvsm.rtl.board`, :func:`rvsm.rtl.fpga.board_top.board_ports`): its data
pairs, a framing / training lane and a forwarded clock pair (:data:`LINK_OVERHEAD_PAIRS`).

**Placement** (:func:`place_links`) follows the pin planner's edge-clock rule, one rule for
both (:func:`rvsm.rtl.fpga.pin_plan.edge_clock_placements`): links only on the left and
right banks (the IOLOGIC gearing), at most two links a side, and either one link alone on
its side spanning both of its banks, or two links sharing one bank. Why this rule: it is
what nextpnr-ecp5 places (the planner's rule was checked by placing small designs, and the
full sensor's 37-pair receive link spans banks 6 and 7 in ``make bench-board``): an edge
clock reaches the other bank of its side through the bank edge-clock bridge
(``ECLKBRIDGECS``, Lattice FPGA-TN-02035 "ECP5 and ECP5-5G High-Speed I/O Interface",
edge clock structure), while nextpnr-ecp5 0.11 gives each link the first free ECLK index
of every bank it touches, so two links in the two banks of one side collide on that
side's CLKDIVF 0. ``scope="side"`` is that rule (the default); ``scope="bank"`` keeps
every link inside one bank (no bridge). Transmit pairs (data, framing and clock) need a
true LVDS driver (an A/B pair); receive pairs take any pair. The counts per bank are
:data:`~rvsm.rtl.fpga.package_io.ECP5_BANKS` (on the ECP5-85 derived from the planner's
pin tables); ``tests/rtl/fpga/test_io_budget.py`` checks that the verdict equals
:func:`~rvsm.rtl.fpga.pin_plan.plan_pins` on every ECP5-85 package.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.package_io import BankIo, PackageIo
from rvsm.rtl.fpga.pin_plan import SIDES, LinkSpec, edge_clock_placements

__all__ = ["LINK_OVERHEAD_PAIRS", "SCOPES", "Group", "GroupUse", "IoPlan", "LinkPlan",
           "Placement", "io_plan", "link_plan", "place_links"]

#: Pairs every link adds: a forwarded clock and a framing / training lane.
LINK_OVERHEAD_PAIRS = 2
#: What one link's edge clock reaches: both banks of its side when alone there (the
#: planner's rule, the default), or one bank.
SCOPES = ("side", "bank")


@dataclass(frozen=True)
class LinkPlan:
    """One direction: ``bits_per_s`` of payload, ``bits_per_cycle`` of it per core cycle,
    ``bits_per_pair_per_cycle`` a pair moves, ``rate_per_pair_bps`` and ``data_pairs``."""

    direction: str
    bits_per_s: float
    bits_per_cycle: int
    gearing: str
    bits_per_pair_per_cycle: int
    rate_per_pair_bps: float
    data_pairs: int


def link_plan(direction: str, bits_per_s: float, core_hz: float, gearing: str,
              max_bps_per_pair: float) -> LinkPlan:
    """The data pairs ``bits_per_s`` needs at ``core_hz`` on a gearing of
    ``max_bps_per_pair`` (module docstring)."""
    if not core_hz > 0 or not max_bps_per_pair > 0:
        raise RvsmError(f"core clock and rate per pair must be > 0, got {core_hz:g} Hz "
                        f"and {max_bps_per_pair:g} bit/s")
    per_pair = int(max_bps_per_pair // core_hz)
    per_cycle = math.ceil(bits_per_s / core_hz - 1e-9)
    if per_pair < 1:  # a core clock above the pair's rate: under a bit a cycle per pair
        return LinkPlan(direction, bits_per_s, per_cycle, gearing, 0, max_bps_per_pair,
                        math.ceil(bits_per_s / max_bps_per_pair - 1e-9))
    return LinkPlan(direction, bits_per_s, per_cycle, gearing, per_pair, per_pair * core_hz,
                    -(-per_cycle // per_pair))


@dataclass(frozen=True)
class Group:
    """Pins sharing one edge clock: ``name``, ``pairs``, ``lvds_out_pairs``."""

    name: str
    pairs: int
    lvds_out_pairs: int


@dataclass(frozen=True)
class GroupUse:
    """The data pairs of each direction one group carries (a link each way where > 0)."""

    group: Group
    in_data: int
    out_data: int

    @property
    def pairs_used(self) -> int:
        """Data pairs plus a clock and a framing pair per link."""
        k = LINK_OVERHEAD_PAIRS
        return (self.in_data + (k if self.in_data else 0)
                + self.out_data + (k if self.out_data else 0))


@dataclass(frozen=True)
class Placement:
    """Where the two links go (``uses``: one per group holding a link; empty when they do
    not place) and ``reason``: the binding figure when they do not
    ``(figure, budget, unit)``."""

    uses: tuple[GroupUse, ...]
    reason: tuple[int, int, str] | None = None

    @property
    def placed(self) -> bool:
        return bool(self.uses)


def _group(banks: dict[int, BankIo], side: str, which: tuple[int, ...]) -> Group:
    name = ("left" if side == "L" else "right") + f" (bank{'s' * (len(which) > 1)} " \
        + "+".join(str(b) for b in which) + ")"
    return Group(name, sum(banks[b].pairs for b in which if b in banks),
                 sum(banks[b].lvds_out_pairs for b in which if b in banks))


def place_links(banks: tuple[BankIo, ...], in_data: int, out_data: int,
                scope: str = "side") -> Placement:
    """Place one receive link of ``in_data`` data pairs and one transmit link of
    ``out_data`` (each + :data:`LINK_OVERHEAD_PAIRS`) on ``banks`` under the planner's
    edge-clock rule (module docstring); ``scope="bank"``: every link in one bank."""
    if scope not in SCOPES:
        raise RvsmError(f"link scope must be one of {', '.join(SCOPES)}, got {scope!r}")
    k = LINK_OVERHEAD_PAIRS
    by_bank = {b.bank: b for b in banks if b.edge_clock}
    links = [LinkSpec("rx0", "rx", in_data + k - 1), LinkSpec("tx0", "tx", out_data + k - 1)]
    need = {"rx0": in_data + k, "tx0": out_data + k}
    for where in edge_clock_placements(links):
        if scope == "bank" and any(len(b) > 1 for _, b in where.values()):
            continue
        groups = {n: _group(by_bank, side, b) for n, (side, b) in where.items()}
        if where["rx0"] == where["tx0"]:  # two links in one bank
            g = groups["rx0"]
            ok = need["tx0"] <= g.lvds_out_pairs and need["rx0"] + need["tx0"] <= g.pairs
            uses = (GroupUse(g, in_data, out_data),)
        else:
            ok = (need["tx0"] <= groups["tx0"].lvds_out_pairs
                  and need["rx0"] <= groups["rx0"].pairs)
            uses = (GroupUse(groups["rx0"], in_data, 0), GroupUse(groups["tx0"], 0, out_data))
        if ok:
            return Placement(uses)
    spans = [(s, b) for s, pair in SIDES.items()
             for b in ((pair,) if scope == "side" else ()) + ((pair[0],), (pair[1],))]
    best = [_group(by_bank, s, b) for s, b in spans]
    most_lvds = max((g.lvds_out_pairs for g in best), default=0)
    most_pairs = max((g.pairs for g in best), default=0)
    if need["tx0"] > most_lvds:
        return Placement((), (need["tx0"], most_lvds, "true-LVDS transmit pairs on one "
                                                      "edge clock"))
    if need["rx0"] > most_pairs:
        return Placement((), (need["rx0"], most_pairs, "receive pairs on one edge clock"))
    return Placement((), (need["rx0"] + need["tx0"], most_pairs, "pairs on one side"))


@dataclass(frozen=True)
class IoPlan:
    """Both directions of one camera on one package, and their placement."""

    package: str
    core_hz: float
    scope: str
    input: LinkPlan
    output: LinkPlan
    placement: Placement
    edge_pairs: int
    edge_lvds_out_pairs: int

    @property
    def fits(self) -> bool:
        """Both links placed, with their clock and framing pairs."""
        return self.placement.placed

    @property
    def links(self) -> tuple[int, int]:
        """``(input links, output links)`` of the placement."""
        return (sum(1 for u in self.placement.uses if u.in_data),
                sum(1 for u in self.placement.uses if u.out_data))

    @property
    def pairs_needed(self) -> int:
        """Pairs of both links: data, framing and forwarded clock."""
        return self.input.data_pairs + self.output.data_pairs + 2 * LINK_OVERHEAD_PAIRS

    def verdict(self) -> tuple[float, float, str, str]:
        """``(figure, budget, unit, detail)``: the binding budget, as the checks say it."""
        i, o, p = self.input, self.output, self.placement
        rates = (f"in {i.bits_per_s / 1e9:.1f} Gbit/s = {i.data_pairs} pairs x "
                 f"{i.bits_per_pair_per_cycle} bits per core cycle, out "
                 f"{o.bits_per_s / 1e9:.1f} Gbit/s = {o.data_pairs} pairs, {i.gearing} "
                 f"gearing at {i.rate_per_pair_bps / 1e6:g} Mbit/s per pair, one link each "
                 f"way +{LINK_OVERHEAD_PAIRS} pairs (clock, framing), edge clocks per "
                 f"{self.scope}, {self.package}")
        if not p.placed:
            figure, budget, unit = p.reason
            return (figure, budget, unit, f"{rates}; the links do not place")
        where = "; ".join(f"{u.group.name}: " + " + ".join(
            f"{d} {n + LINK_OVERHEAD_PAIRS}" for d, n in (("rx", u.in_data),
                                                          ("tx", u.out_data)) if n)
            for u in p.uses)
        return (self.pairs_needed, self.edge_pairs, "pairs", f"{rates}; {where}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures."""
        figure, budget, unit, detail = self.verdict()
        return {"package": self.package, "core_mhz": self.core_hz / 1e6, "scope": self.scope,
                "fits": self.fits, "figure": figure, "budget": budget, "unit": unit,
                "detail": detail,
                "input": vars(self.input), "output": vars(self.output),
                "links": {"in": self.links[0], "out": self.links[1]},
                "pairs_needed": self.pairs_needed,
                "edge_pairs": self.edge_pairs,
                "edge_lvds_out_pairs": self.edge_lvds_out_pairs,
                "groups": [{"group": u.group.name, "pairs": u.group.pairs,
                            "lvds_out_pairs": u.group.lvds_out_pairs, "in_data": u.in_data,
                            "out_data": u.out_data, "pairs_used": u.pairs_used}
                           for u in self.placement.uses]}


def io_plan(layout: Any, rate_hz: float, package: PackageIo, core_hz: float,
            gearing: str = "x2", scope: str = "side") -> IoPlan:
    """The :class:`IoPlan` of ``layout`` (an ArrayContract or a StateLayout: height,
    width, ADC bits and scales) at ``rate_hz`` steps/s on ``package`` at ``core_hz``."""
    if package.estimate_only:
        raise RvsmError(f"{package.name}: no per-bank I/O figures (estimate only)")
    g = package.gearing(gearing)
    if g.max_mbps_per_pair is None:
        raise RvsmError(f"{package.name}: the {gearing} gearing's rate per pair is "
                        f"unconfirmed; use one with a rate ({g.source})")
    if scope not in SCOPES:
        raise RvsmError(f"link scope must be one of {', '.join(SCOPES)}, got {scope!r}")
    scales = getattr(layout, "num_scales", None) or len(layout.scales)
    pixels_per_s = layout.height * layout.width * rate_hz
    max_bps = g.max_mbps_per_pair * 1e6
    inp = link_plan("in", pixels_per_s * layout.adc_bits, core_hz, gearing, max_bps)
    out = link_plan("out", pixels_per_s * scales * 2, core_hz, gearing, max_bps)
    edge = [b for b in package.banks if b.edge_clock or not g.edge_banks]
    return IoPlan(package.name, core_hz, scope, inp, out,
                  place_links(package.banks, inp.data_pairs, out.data_pairs, scope),
                  sum(b.pairs for b in edge), sum(b.lvds_out_pairs for b in edge))
