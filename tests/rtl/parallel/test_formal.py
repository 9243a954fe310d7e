"""The parallel array's formal harness: its properties are proven by k-induction at a tiny
size in both reset modes, every cover is reachable, and the seeded threshold bug is caught
(a few seconds of solver time each)."""

from __future__ import annotations

import dataclasses

import pytest

from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.formal_harness import property_at
from rvsm.rtl.parallel.harnesses import ParallelProperties
from rvsm.sim.formal.sby import run_sby

ASSERTS = {"valid.latency", "receptive.sum", "saturation.high_rail", "saturation.low_rail",
           "fire.spike_implies_threshold", "fire.threshold_implies_spike",
           "hold.no_strobe", "clear.zeroes_state", "reset.domain", "threshold.write",
           "threshold.kept"}


def test_registered_as_the_parallel_properties(formal_point):
    factory = get_architecture("parallel").formal["properties"]
    harness = factory(formal_point.contract(), mutation=None)
    assert isinstance(harness, ParallelProperties) and harness.provable
    assert {p.name for p in harness.statements() if p.kind == "assert"} >= ASSERTS


@pytest.mark.parametrize("model, reset", [("dog2", "subtract"), ("fsm", "zero")])
def test_statements_name_every_property(formal_point, model, reset):
    contract = dataclasses.replace(formal_point, model=model, reset=reset).contract()
    props = ParallelProperties(contract).statements()
    asserts = {p.name for p in props if p.kind == "assert"}
    covers = {p.name for p in props if p.kind == "cover"}
    assert asserts == ASSERTS | {f"reset.{reset}"}
    assert "cover.spike_pos" in covers
    assert {"cover.saturate_high", "cover.clear_after_spike"} <= covers
    assert ("cover.saturate_low" in covers) == contract.signed
    assert ("cover.spike_neg" in covers) == contract.signed
    assert all(p.src.split(":")[0].endswith("rtl/parallel/harnesses.py") for p in props)
    # sby names a failing statement by its line: one property per line
    assert len({p.src for p in props}) == len(props)


@pytest.mark.parametrize("reset", ["subtract", "zero"])
def test_shipped_array_is_proven(formal_point, tmp_path, reset):
    contract = dataclasses.replace(formal_point, reset=reset).contract()
    harness = ParallelProperties(contract)
    result = run_sby(harness, tmp_path, mode="prove", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


def test_every_cover_is_reached(formal_point, tmp_path):
    harness = ParallelProperties(formal_point.contract())
    result = run_sby(harness, tmp_path, mode="cover", depth=harness.cover_depth)
    assert result.status == "PASS", result.failed


def test_threshold_off_by_one_is_caught(formal_point, tmp_path):
    harness = ParallelProperties(formal_point.contract(),
                                 mutation="parallel.threshold_off_by_one")
    result = run_sby(harness, tmp_path, mode="bmc", depth=4)
    assert result.status == "FAIL"
    props = harness.statements()
    failing = {property_at(props, loc).name for loc in result.failed}
    assert "fire.threshold_implies_spike" in failing
    assert "fire.spike_implies_threshold" not in failing  # > still implies >=
