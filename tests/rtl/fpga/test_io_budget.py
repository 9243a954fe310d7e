"""Lane and bank arithmetic of the I/O budget against slow straightforward counts."""

from __future__ import annotations

import itertools
import math
import random
from pathlib import Path
from types import SimpleNamespace

import pytest

from rvsm.model.fixed.point_toml import load_point_file
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.devices import get_budget
from rvsm.rtl.fpga.io_budget import (
    LINK_OVERHEAD_PAIRS,
    Group,
    io_plan,
    link_plan,
    place_links,
)

ROOT = Path(__file__).resolve().parents[3]


def _pairs_by_counting(bits_per_s: float, core_hz: float, max_bps: float) -> tuple[int, int]:
    """(bits a pair moves per core cycle, data pairs): one core cycle's bits dealt to pairs
    one bit at a time, each pair taking bits until a cycle of its rate is full."""
    per_pair = 0
    while (per_pair + 1) * core_hz <= max_bps:
        per_pair += 1
    bits = 0
    while bits * core_hz < bits_per_s - 1e-6:
        bits += 1
    pairs, room = 0, 0
    for _ in range(bits):
        if room == 0:
            pairs, room = pairs + 1, per_pair
        room -= 1
    return per_pair, pairs


@pytest.mark.parametrize("h,w,rate,bits,core_mhz", [
    (250, 400, 40e3, 7, 100.0), (250, 400, 40e3, 4, 100.0), (64, 64, 1e3, 7, 0.5),
    (250, 400, 40e3, 7, 80.0), (250, 400, 40e3, 7, 125.0), (120, 160, 30e3, 10, 48.0),
])
def test_link_plan_is_the_bit_by_bit_count(h, w, rate, bits, core_mhz) -> None:
    bps, core = h * w * rate * bits, core_mhz * 1e6
    plan = link_plan("in", bps, core, "x2", 800e6)
    assert (plan.bits_per_pair_per_cycle, plan.data_pairs) == _pairs_by_counting(bps, core,
                                                                                 800e6)
    assert plan.rate_per_pair_bps == plan.bits_per_pair_per_cycle * core <= 800e6
    assert plan.data_pairs * plan.rate_per_pair_bps >= bps


def test_shipped_point_rates_pairs_and_words() -> None:
    point, _ = load_point_file(ROOT / "points" / "ecp5-85-40khz.toml")
    pk = get_budget("ecp5-85").package_io()
    p = io_plan(point.contract(), 40e3, pk, 100e6)
    assert (p.input.bits_per_s, p.input.bits_per_cycle, p.input.data_pairs) == (28e9, 280, 35)
    assert (p.output.bits_per_s, p.output.bits_per_cycle, p.output.data_pairs) == (16e9, 160,
                                                                                   20)
    assert p.input.bits_per_pair_per_cycle == 8 and p.input.rate_per_pair_bps == 800e6
    assert pk.name == "LFE5U-85F CABGA381" and not p.fits
    used = sum(u.pairs_used for u in p.placement.uses)
    assert used <= p.edge_pairs == 65 and p.edge_lvds_out_pairs == 33


def _best_by_brute_force(groups, out_data: int) -> int:
    """Most input data pairs beside ``out_data`` output pairs, every choice per group."""
    k = LINK_OVERHEAD_PAIRS
    choices = []
    for g in groups:
        opts = []
        for o in range(0, g.pairs + 1):
            o_used = o + k if o else 0
            if o_used > min(g.lvds_out_pairs, g.pairs):
                continue
            for i in range(0, g.pairs + 1):
                if o_used + (i + k if i else 0) <= g.pairs:
                    opts.append((o, i))
        choices.append(opts)
    best = -1
    for combo in itertools.product(*choices):
        if sum(o for o, _ in combo) >= out_data:
            best = max(best, sum(i for _, i in combo))
    return best


def test_placement_is_the_brute_force_best() -> None:
    rng = random.Random(7)
    for _ in range(60):
        groups = tuple(Group(f"g{n}", p, rng.randint(0, (p + 1) // 2))
                       for n, p in enumerate(rng.randint(0, 9) for _ in range(rng.randint(1, 3))))
        out_data = rng.randint(0, 8)
        in_data = rng.randint(0, 10)
        got = place_links(groups, out_data, in_data)
        want = _best_by_brute_force(groups, out_data)
        assert got.max_in == want, (groups, out_data)
        if want >= 0:
            assert sum(u.out_data for u in got.uses) == out_data
            assert sum(u.in_data for u in got.uses) == min(in_data, want)
            for u in got.uses:
                assert u.pairs_used <= u.group.pairs
                assert (u.out_data + LINK_OVERHEAD_PAIRS if u.out_data else 0) <= \
                    u.group.lvds_out_pairs


def test_io_plan_refuses_what_it_cannot_plan() -> None:
    lay = SimpleNamespace(height=8, width=8, adc_bits=7, num_scales=1)
    with pytest.raises(RvsmError, match="estimate only"):
        io_plan(lay, 1e3, get_budget("gw2a-18").package_io(), 1e6)
    pk = get_budget("ecp5-85").package_io()
    with pytest.raises(RvsmError, match="7:1 gearing's rate per pair is unconfirmed"):
        io_plan(lay, 1e3, pk, 1e6, gearing="7:1")
    with pytest.raises(RvsmError, match="link scope must be one of bank, side"):
        io_plan(lay, 1e3, pk, 1e6, scope="chip")
    fast = link_plan("in", 28e9, 4e9, "x2", 800e6)  # a core clock above the pair rate
    assert (fast.bits_per_pair_per_cycle, fast.data_pairs) == (0, math.ceil(28e9 / 800e6))
