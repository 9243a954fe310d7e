"""The compositional equivalence checks (``window``, ``sums``, ``composed``): each holds
on the shipped array at 3x4 with 2 lanes, each can fail (a padding bug breaks the window
lemma, sums built from another model's kernels break the sum lemma's linear forms, a
register-free tree that is not the pipeline's breaks its retiming part, swapped lanes
break the composed miter), and the composed miter's assumption leaves its cover
reachable."""

from __future__ import annotations

import dataclasses

import pytest

from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.formal_harness import property_at
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.formal_lemmas import (
    ComposedEquivalence,
    StreamSumLemma,
    StreamWindowLemma,
)
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
                "sums": (StreamSumLemma, {"sums.retiming", "sums.linear_forms"}),
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


def test_sum_lemma_covers_every_stage_q_output(formal_point):
    contract = _contract(formal_point)
    lemma = StreamSumLemma(contract, 2)
    assert lemma.depth == StreamGeometry(contract, 2).sum_stage + 1
    assert lemma.offline_properties == ("sums.linear_forms",)


@pytest.mark.parametrize("model, size, lanes", [
    ("dog2", (3, 4), 2), ("dog4", (3, 4), 2), ("dog4", (3, 6), 3), ("dog4", (3, 3), 1)])
def test_sum_linear_forms_hold_on_the_shipped_sums(formal_point, model, size, lanes):
    assert StreamSumLemma(_contract(formal_point, model, size=size), lanes
                          ).offline_failures() == []


def test_sum_linear_forms_catch_a_wrong_kernel(formal_point):
    """The trees built from dog1's kernels are not the parallel array's gauss1 sums:
    the message names the scale, position, lane and pixel."""
    harness = StreamSumLemma(_contract(formal_point, "gauss1"), 2)
    harness.geometry = StreamGeometry(_contract(formal_point, "dog1"), 2)
    failures = harness.offline_failures()
    assert failures and {name for name, _ in failures} == {"sums.linear_forms"}
    assert failures[0][1].startswith("scale 0, position 0 (row 0, column 0), lane 0: "
                                     "pixel (0, 0) has weight ")


def test_sum_linear_forms_catch_a_wrong_tap(formal_point, monkeypatch):
    """One parallel tap moved by a column (a seeded wrong tap) fails the comparison."""
    import rvsm.rtl.stream.formal_lemmas as lemmas

    real = lemmas.receptive_taps

    def shifted(contract, scale, row, col):
        taps = real(contract, scale, row, col)
        (yy, xx), wt = taps[0]
        return [((yy, (xx + 1) % contract.width), wt)] + taps[1:]

    monkeypatch.setattr(lemmas, "receptive_taps", shifted)
    failures = StreamSumLemma(_contract(formal_point), 2).offline_failures()
    assert failures and all(name == "sums.linear_forms" for name, _ in failures)


def test_sum_lemma_fails_before_the_solver(formal_point, tmp_path):
    """A linear-form failure is the check's counterexample, with no sby run."""
    from rvsm.sim.formal.runner import _run_check

    harness = StreamSumLemma(_contract(formal_point, "gauss1"), 2)
    harness.geometry = StreamGeometry(_contract(formal_point, "dog1"), 2)
    result = _run_check("sums", harness, "bmc", harness.depth, tmp_path, None, "yices",
                        None)
    assert result.status == "fail"
    assert result.counterexample.property == "sums.linear_forms"
    assert "pixel (0, 0)" in result.counterexample.description
    assert not (tmp_path / "sums").exists()


@pytest.mark.parametrize("kind", [
    StreamWindowLemma,
    pytest.param(ComposedEquivalence, marks=pytest.mark.slow),  # 13 s: make regress
])
def test_lemma_holds_on_the_shipped_array(formal_point, tmp_path, kind):
    harness = kind(_contract(formal_point), 2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


def test_sum_lemma_holds_on_the_shipped_sums(formal_point, tmp_path):
    harness = StreamSumLemma(_contract(formal_point, "dog4"), 2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


def test_sum_retiming_catches_a_tree_that_is_not_the_pipeline(formal_point, tmp_path):
    """The register-free side built from another model's trees differs from the
    pipeline: ``sums.retiming`` fails (the solver part can fail too)."""
    import rvsm.rtl.stream.formal_lemmas as lemmas

    harness = StreamSumLemma(_contract(formal_point, "gauss1"), 2)
    other = StreamGeometry(_contract(formal_point, "dog1"), 2)

    real = harness.geometry.stage_q_sums

    def stage_q_sums(pipe, window):
        if isinstance(pipe, lemmas._Unregistered):
            window = {cell: window.get(cell, next(iter(window.values())))
                      for cell in other.window_cells()}
            sums, _ = other.build_sums(pipe, window)
            return [[pipe.at(t, other.sum_stage) for t in lane] for lane in sums], 0
        return real(pipe, window)

    harness.geometry.stage_q_sums = stage_q_sums
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "FAIL"
    assert _failing(harness, result) == {"sums.retiming"}


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
