"""The tail (``rtl/stream/output_stage.py``) against the numpy models of its output rules
in ``amaranth.sim``: random sums, accumulators, thresholds, fresh frames and stalls, both
sensors, both reset modes; and the models against the contract's integrators."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.contract import FixedEventIntegrator, FixedIntegrator
from rvsm.model.fixed.widths import signed_range
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import Output
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.output_stage import (
    OUTPUT_TAILS,
    EventTail,
    OutputStage,
    SpikeTail,
    output_tail,
)
from tests.conftest import model_contract


def _pack(values, bits: int) -> int:  # noqa: ANN001 - a sequence of ints
    return sum((int(v) & ((1 << bits) - 1)) << (i * bits) for i, v in enumerate(values))


def _bits(word: int, count: int) -> np.ndarray:
    return np.array([(word >> k) & 1 for k in range(count)], dtype=bool)


def _contract(sensor: str, reset: str = "subtract", acc_bits: int = 8):
    c = model_contract("dog2", 6, 4, frac_bits=5, acc_bits=acc_bits, shift=2, reset=reset)
    return dataclasses.replace(c, sensor=sensor)


def _run(amaranth_sim, geo: StreamGeometry, mutation: str | None = None,
         edges: int = 250) -> int:
    """Drive an :class:`OutputStage`; assert the written-back words and the output beats
    against the rule's model; return the beats compared."""
    c = geo.contract
    dut = OutputStage(geo, mutation=mutation)
    rule = output_tail(c)
    p, wa, tw, scales = geo.lanes, c.accumulator_bits, c.threshold_bits, c.num_scales
    lo, hi = signed_range(wa)
    rng = np.random.default_rng(3)
    taken = []  # the inputs at each advance edge
    compared = []

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        while len(taken) < edges:
            advance = bool(rng.random() < 0.7)
            sums = np.stack([rng.integers(*c.sum_range(s), p, endpoint=True)
                             for s in range(scales)])  # (S, P)
            acc = rng.integers(lo, hi, (scales, p), endpoint=True)
            acc[:, rng.random(p) < 0.3] = rng.choice([lo, hi, 0, -1, 1])
            thr = rng.integers(1, hi, (scales, p), endpoint=True)
            fresh = bool(rng.random() < 0.2)
            valid = bool(rng.random() < 0.8)
            row, group = int(rng.integers(0, c.height)), int(rng.integers(0, geo.groups))
            ctx.set(dut.ctl.advance, int(advance))
            for s in range(scales):
                ctx.set(dut.words.acc[s], _pack(acc[s], wa))
                ctx.set(dut.words.thr[s], _pack(thr[s], tw))
                for i in range(p):
                    ctx.set(dut.sums[i][f"s{s}"], int(sums[s, i]) % (1 << geo.sum_bits(s)))
            ctx.set(dut.fresh, int(fresh))
            for name, value in (("en", advance and valid), ("valid", valid), ("row", row),
                                ("group", group), ("last", row == c.height - 1)):
                ctx.set(getattr(dut.position, name), int(value))
            await ctx.tick()
            assert ctx.get(dut.spikes.valid) == int(advance and valid)
            if not advance:
                continue
            shifted = sums >> c.shift  # floor division, as the contract's shift
            taken.append((acc, fresh, shifted, thr, row, group))
            if len(taken) >= 2:  # the word written back: two advance edges on
                a, f, sh, th = taken[-2][:4]
                _, _, after = rule.model(a, np.full(a.shape, f), sh, th)
                for s in range(scales):
                    got = ctx.get(dut.write_data[s])
                    assert got == _pack(after[s], wa), ("write-back", len(taken), s)
            if len(taken) >= 3:  # the output register: three advance edges on
                a, f, sh, th = taken[-3][:4]
                pos, neg, _ = rule.model(a, np.full(a.shape, f), sh, th)
                out = dut.spikes.payload
                assert (ctx.get(out.row), ctx.get(out.group)) == (row, group)
                assert list(_bits(ctx.get(out.pos), scales * p)) == list(pos.ravel()), \
                    ("pos", len(taken))
                assert list(_bits(ctx.get(out.neg), scales * p)) == list(neg.ravel()), \
                    ("neg", len(taken))
                compared.append(len(taken))

    amaranth_sim.run(dut, bench)
    return len(compared)


@pytest.mark.parametrize(("sensor", "reset"), [("spike", "subtract"), ("spike", "zero"),
                                               ("dvs", "subtract")])
def test_tail_follows_its_rule(amaranth_sim, sensor: str, reset: str) -> None:
    geo = StreamGeometry(_contract(sensor, reset), 2)
    assert _run(amaranth_sim, geo) > 200


@pytest.mark.parametrize("mutation", ["stream.threshold_off_by_one", "stream.no_saturation",
                                      "stream.no_reset_on_spike", "stream.swapped_lanes",
                                      "stream.shift_off_by_one", "stream.stale_threshold",
                                      "stream.zero_instead_of_subtract",
                                      "stream.no_negative_spikes",
                                      "stream.clear_forgets_scale0"])
def test_a_tail_bug_disagrees_with_the_model(amaranth_sim, mutation: str) -> None:
    geo = StreamGeometry(_contract("spike"), 2)
    with pytest.raises(AssertionError):
        _run(amaranth_sim, geo, mutation)


def test_the_rules_are_the_contract_s_integrators() -> None:
    """One step of :class:`FixedIntegrator` / :class:`FixedEventIntegrator` from any
    state equals the rule's model (the tail compares the pre-saturation total: the same,
    since thresholds are at most the high rail)."""
    rng = np.random.default_rng(9)
    shape = (2, 5, 7)
    for reset in ("zero", "subtract"):
        c = _contract("spike", reset, acc_bits=8)
        lo, hi = signed_range(8)
        acc = rng.integers(lo, hi, shape, endpoint=True)
        thr = rng.integers(1, hi, shape, endpoint=True)
        sums = rng.integers(-300, 300, shape)
        integrator = FixedIntegrator(thr, 8, c.signed, reset)
        integrator.acc[...] = acc
        spikes = integrator.step(sums)
        pos, neg, after = SpikeTail(c).model(acc, np.zeros(shape, bool), sums, thr)
        np.testing.assert_array_equal(spikes, pos.astype(np.int8) - neg.astype(np.int8))
        np.testing.assert_array_equal(integrator.acc, after)
    c = _contract("dvs", acc_bits=8)
    ref = rng.integers(lo, hi, shape, endpoint=True)
    events = FixedEventIntegrator(thr, 8)
    capture = events.step(sums)  # a fresh frame: captures clamp(sums)
    pos, neg, after = EventTail(c).model(ref, np.ones(shape, bool), sums, thr)
    assert not capture.any() and not pos.any() and not neg.any()
    np.testing.assert_array_equal(events.ref, after)
    events.ref[...] = ref
    got = events.step(sums)
    pos, neg, after = EventTail(c).model(ref, np.zeros(shape, bool), sums, thr)
    np.testing.assert_array_equal(got, pos.astype(np.int8) - neg.astype(np.int8))
    np.testing.assert_array_equal(events.ref, after)


def test_one_table_chooses_the_rule() -> None:
    assert set(OUTPUT_TAILS) == set(Output)  # every output rule has its tail
    assert isinstance(output_tail(_contract("spike")), SpikeTail)
    assert isinstance(output_tail(_contract("dvs")), EventTail)
    with pytest.raises(RvsmError, match="sensor must be one of"):  # refused by its kind
        output_tail(_contract("radar"))
