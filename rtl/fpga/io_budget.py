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
``ceil(bits_per_s / max)`` pairs. Every **link** adds a forwarded clock pair and a framing /
training pair (:data:`LINK_OVERHEAD_PAIRS`).

**Placement** (:func:`place_links`): a link lives in one *group* of pins sharing its edge
clock: one bank (``scope="bank"``, the bank's own ECLKSYNCB) or one side (``"side"``,
both banks of a side on one edge clock through ECLKBRIDGECS or a PLL). Output pairs need
a true LVDS driver (an A/B pair); input pairs take any pair left. Per group at most one
link each way; :func:`place_links` finds the placement that carries the outputs and the
most input pairs (an exact small dynamic programme over the groups).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.package_io import BankIo, PackageIo

__all__ = ["LINK_OVERHEAD_PAIRS", "SCOPES", "Group", "GroupUse", "IoPlan", "LinkPlan",
           "Placement", "groups_of", "io_plan", "link_plan", "place_links"]

#: Pairs every link adds: a forwarded clock and a framing / training lane.
LINK_OVERHEAD_PAIRS = 2
#: What one link's edge clock reaches: one bank, or both banks of a side.
SCOPES = ("bank", "side")


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


def groups_of(banks: tuple[BankIo, ...], scope: str, edge_only: bool = True
              ) -> tuple[Group, ...]:
    """The link groups of ``banks`` (only edge-clock banks when ``edge_only``)."""
    if scope not in SCOPES:
        raise RvsmError(f"link scope must be one of {', '.join(SCOPES)}, got {scope!r}")
    use = [b for b in banks if b.edge_clock or not edge_only]
    if scope == "bank":
        return tuple(Group(f"bank {b.bank}", b.pairs, b.lvds_out_pairs) for b in use)
    sides: dict[str, list[BankIo]] = {}
    for b in use:
        sides.setdefault(b.side, []).append(b)
    return tuple(Group(f"{s} (banks {', '.join(str(b.bank) for b in bs)})",
                       sum(b.pairs for b in bs), sum(b.lvds_out_pairs for b in bs))
                 for s, bs in sides.items())


@dataclass(frozen=True)
class GroupUse:
    """Data pairs of each direction one group carries (a link each way where > 0)."""

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
    """The best placement: ``uses`` per group, ``max_in`` input data pairs the groups
    carry beside the outputs (-1: the outputs do not place), ``max_out`` output data pairs
    the groups carry at most."""

    uses: tuple[GroupUse, ...]
    max_in: int
    max_out: int

    def fits(self, in_data: int) -> bool:
        """The outputs place and ``in_data`` input pairs fit beside them."""
        return self.max_in >= in_data


def _out_options(g: Group) -> list[int]:
    k = LINK_OVERHEAD_PAIRS
    return [0] + list(range(1, max(0, min(g.lvds_out_pairs, g.pairs) - k) + 1))


def _in_left(g: Group, out: int) -> int:
    left = g.pairs - (out + LINK_OVERHEAD_PAIRS if out else 0)
    return max(0, left - LINK_OVERHEAD_PAIRS)


def place_links(groups: tuple[Group, ...], out_data: int, in_data: int) -> Placement:
    """Place ``out_data`` output and ``in_data`` input data pairs in ``groups`` (module
    docstring): per group the output data it takes, the rest of its pairs to inputs."""
    max_out = sum(max(_out_options(g)) for g in groups)
    # best[o] = (most input pairs, choices) with o = output pairs placed, capped at out_data
    best: dict[int, tuple[int, tuple[int, ...]]] = {0: (0, ())}
    for g in groups:
        nxt: dict[int, tuple[int, tuple[int, ...]]] = {}
        for o_sum, (i_sum, picks) in best.items():
            for o in _out_options(g):
                key = min(out_data, o_sum + o)
                cand = (i_sum + _in_left(g, o), picks + (o,))
                if key not in nxt or cand[0] > nxt[key][0]:
                    nxt[key] = cand
        best = nxt
    if out_data not in best:
        return Placement((), -1, max_out)
    max_in, picks = best[out_data]
    outs, need_o = [], out_data
    for o in picks:
        outs.append(min(o, need_o))
        need_o -= outs[-1]
    ins, need_i = [0] * len(groups), in_data  # the roomiest groups first: fewest links
    for k in sorted(range(len(groups)), key=lambda k: -_in_left(groups[k], outs[k])):
        ins[k] = min(_in_left(groups[k], outs[k]), need_i)
        need_i -= ins[k]
    return Placement(tuple(GroupUse(g, i, o) for g, i, o in zip(groups, ins, outs,
                                                                 strict=True)),
                     max_in, max_out)


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
        """Every output and input pair placed, with its links' clock and framing pairs."""
        return self.placement.fits(self.input.data_pairs)

    @property
    def links(self) -> tuple[int, int]:
        """``(input links, output links)`` of the placement."""
        return (sum(1 for u in self.placement.uses if u.in_data),
                sum(1 for u in self.placement.uses if u.out_data))

    def verdict(self) -> tuple[float, float, str, str]:
        """``(figure, budget, unit, detail)``: the binding budget, as the checks say it."""
        i, o, p = self.input, self.output, self.placement
        rates = (f"in {i.bits_per_s / 1e9:.1f} Gbit/s = {i.data_pairs} pairs x "
                 f"{i.bits_per_pair_per_cycle} bits per core cycle, out "
                 f"{o.bits_per_s / 1e9:.1f} Gbit/s = {o.data_pairs} pairs, {i.gearing} "
                 f"gearing at {i.rate_per_pair_bps / 1e6:g} Mbit/s per pair, +"
                 f"{LINK_OVERHEAD_PAIRS} pairs (clock, framing) per link, links per "
                 f"{self.scope}, {self.package}")
        if p.max_in < 0:
            return (o.data_pairs, p.max_out, "true-LVDS output data pairs",
                    f"{rates}; the outputs do not place")
        li, lo = self.links
        if not self.fits:
            return (i.data_pairs, p.max_in, "input data pairs",
                    f"{rates}; beside the outputs the banks carry {p.max_in}")
        used = sum(u.pairs_used for u in p.uses)
        return (used, self.edge_pairs, "pairs",
                f"{rates}; {li} input and {lo} output links; "
                f"{o.data_pairs + LINK_OVERHEAD_PAIRS * lo} of "
                f"{self.edge_lvds_out_pairs} true-LVDS pairs")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures."""
        figure, budget, unit, detail = self.verdict()
        return {"package": self.package, "core_mhz": self.core_hz / 1e6, "scope": self.scope,
                "fits": self.fits, "figure": figure, "budget": budget, "unit": unit,
                "detail": detail,
                "input": vars(self.input), "output": vars(self.output),
                "links": {"in": self.links[0], "out": self.links[1]},
                "edge_pairs": self.edge_pairs,
                "edge_lvds_out_pairs": self.edge_lvds_out_pairs,
                "max_input_data_pairs": self.placement.max_in,
                "max_output_data_pairs": self.placement.max_out,
                "groups": [{"group": u.group.name, "pairs": u.group.pairs,
                            "lvds_out_pairs": u.group.lvds_out_pairs, "in_data": u.in_data,
                            "out_data": u.out_data, "pairs_used": u.pairs_used}
                           for u in self.placement.uses]}


def io_plan(layout: Any, rate_hz: float, package: PackageIo, core_hz: float,
            gearing: str = "x2", scope: str = "bank") -> IoPlan:
    """The :class:`IoPlan` of ``layout`` (an ArrayContract or a StateLayout: height,
    width, ADC bits and scales) at ``rate_hz`` steps/s on ``package`` at ``core_hz``."""
    if package.estimate_only:
        raise RvsmError(f"{package.name}: no per-bank I/O figures (estimate only)")
    g = package.gearing(gearing)
    if g.max_mbps_per_pair is None:
        raise RvsmError(f"{package.name}: the {gearing} gearing's rate per pair is "
                        f"unconfirmed; use one with a rate ({g.source})")
    scales = getattr(layout, "num_scales", None) or len(layout.scales)
    pixels_per_s = layout.height * layout.width * rate_hz
    max_bps = g.max_mbps_per_pair * 1e6
    inp = link_plan("in", pixels_per_s * layout.adc_bits, core_hz, gearing, max_bps)
    out = link_plan("out", pixels_per_s * scales * 2, core_hz, gearing, max_bps)
    groups = groups_of(package.banks, scope, edge_only=g.edge_banks)
    return IoPlan(package.name, core_hz, scope, inp, out,
                  place_links(groups, out.data_pairs, inp.data_pairs),
                  sum(gr.pairs for gr in groups), sum(gr.lvds_out_pairs for gr in groups))
