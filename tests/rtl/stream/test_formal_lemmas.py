"""The compositional equivalence checks (``window``, ``sums``, ``composed``): each holds
on the shipped array at 3x4 with 2 lanes, each can fail (a padding bug breaks the window
lemma, sums built from another model's kernels break the sum lemma, swapped lanes break
the composed miter), and the composed miter's assumption leaves its cover reachable."""

from __future__ import annotations

import dataclasses

import pytest

from rvsm.rtl.architectures import get_architecture
from rvsm.rtl.formal import property_at
from rvsm.rtl.stream.formal_lemmas import (
    ComposedEquivalence,
    StreamSumLemma,
    StreamWindowLemma,
)
from rvsm.rtl.stream.geometry import StreamGeometry
from rvsm.sim.formal.sby import run_sby


def _contract(point, model: str = "dog2", reset: str = "subtract", size=(3, 4)):
    h, w = size
    return dataclasses.replace(point, height=h, width=w, model=model, reset=reset).contract()


def _failing(harness, result) -> set[str]:
    props = harness.statements()
    return {property_at(props, loc).name for loc in result.failed}


def test_lemmas_are_registered_and_name_their_properties(formal_point):
    checks = get_architecture("stream").formal
    contract = _contract(formal_point)
    expected = {"window": (StreamWindowLemma, {"window.codes"}),
                "sums": (StreamSumLemma, {"sums.stage_q"}),
                "composed": (ComposedEquivalence, {
                    "equivalence.spikes", "equivalence.spikes_early",
                    "equivalence.accumulators", "equivalence.accumulators_early"})}
    for name, (kind, asserts) in expected.items():
        harness = checks[name](contract, lanes=2)
        assert isinstance(harness, kind)
        props = harness.statements()
        assert {p.name for p in props if p.kind == "assert"} == asserts
    assumes = {p.name for p in ComposedEquivalence(contract, 2).statements()
               if p.kind == "assume"}
    assert "assume.sums" in assumes


def test_sum_lemma_schedules_every_position_scale_and_lane(formal_point):
    contract = _contract(formal_point)
    geo = StreamGeometry(contract, 2)
    lemma = StreamSumLemma(contract, 2)
    assert sorted(lemma.schedule) == sorted(
        (a, s, i) for a in range(geo.beats_per_frame) for s in range(contract.num_scales)
        for i in range(2))
    assert lemma.depth == geo.sum_stage - 1 + len(lemma.schedule)


@pytest.mark.parametrize("kind", [
    StreamWindowLemma,
    pytest.param(ComposedEquivalence, marks=pytest.mark.slow),  # 13 s: make regress
])
def test_lemma_holds_on_the_shipped_array(formal_point, tmp_path, kind):
    harness = kind(_contract(formal_point), 2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


def test_sum_lemma_holds_on_the_shipped_sums(formal_point, tmp_path):
    harness = StreamSumLemma(_contract(formal_point, "dog1"), 2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


def test_sum_lemma_catches_wrong_sums(formal_point, tmp_path):
    """The pipeline built from another model's kernel (dog1's centre-surround instead
    of gauss1's single tap) is not the parallel array's sum."""
    harness = StreamSumLemma(_contract(formal_point, "gauss1"), 2)
    harness.geometry = StreamGeometry(_contract(formal_point, "dog1"), 2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "FAIL"
    assert _failing(harness, result) == {"sums.stage_q"}


@pytest.mark.parametrize("kind, mutation, broken", [
    (StreamWindowLemma, "stream.top_padding_off_by_one", "window.codes"),
    pytest.param(ComposedEquivalence, "stream.swapped_lanes", "equivalence.spikes",
                 marks=pytest.mark.slow),
])
def test_lemma_catches_a_seeded_bug(formal_point, tmp_path, kind, mutation, broken):
    harness = kind(_contract(formal_point), 2, mutation)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "FAIL"
    assert broken in _failing(harness, result)


@pytest.mark.slow
def test_composed_assumption_leaves_two_frames_reachable(formal_point, tmp_path):
    """An assumption that contradicted the design would make every assertion hold
    vacuously: the cover at the end of the second frame's comparison is still reached."""
    harness = ComposedEquivalence(_contract(formal_point), 2)
    result = run_sby(harness, tmp_path, mode="cover", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]
