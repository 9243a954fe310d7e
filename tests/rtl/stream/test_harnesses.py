"""The streaming array's formal harnesses: every check is registered and names its
properties; at 3x4 with 2 lanes every property check holds to two frames plus the lag
and the bounded equivalence with the parallel array holds (seconds each); seeded bugs
give counterexamples naming the property they break. The whole matrix of models, lane
counts and reset modes runs in ``make formal``."""

from __future__ import annotations

import dataclasses
import re

import pytest

from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.formal_harness import property_at
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.harnesses import (
    PROPERTY_GROUPS,
    SYNTHESISED_GROUPS,
    StreamEquivalence,
    StreamProperties,
    stream_check,
)
from rvsm.sim.formal.sby import run_sby

GROUP_ASSERTS = {
    "protocol": {"handshake.ready", "output.one_per_beat", "output.raster_order",
                 "rmw.no_read_while_pending"},
    "state": {"state.fresh_after_clear", "state.read_back"},
    "thresholds": {"threshold.timing", "threshold.read_timing", "threshold.memory",
                   "threshold.read_stage", "threshold.compare_stage"},
    "tail": {"saturation.clamps", "fire.spike_implies_threshold",
             "fire.threshold_implies_spike"},
}


def _contract(point, model: str = "dog2", reset: str = "subtract", size=(3, 4)):
    h, w = size
    return dataclasses.replace(point, height=h, width=w, model=model, reset=reset).contract()


def test_every_check_is_registered(formal_point):
    checks = get_architecture("stream").formal
    assert set(checks) == {*PROPERTY_GROUPS, "equivalence", "window", "sums", "composed"}
    contract = _contract(formal_point)
    for group in PROPERTY_GROUPS:
        harness = checks[group](contract, mutation=None, lanes=2)
        assert isinstance(harness, StreamProperties) and harness.groups == (group,)
        harness.statements()
    equivalence = checks["equivalence"](contract, lanes=2)
    assert isinstance(equivalence, StreamEquivalence)
    assert equivalence.inputs == {"stalls": 0, "clears": 0}
    assert {p.name for p in equivalence.statements() if p.kind == "assert"} == {
        "equivalence.spikes", "equivalence.spikes_early", "equivalence.accumulators",
        "equivalence.accumulators_early"}
    srcs = [p.src for p in equivalence.statements() if p.kind != "assume"]
    assert len(set(srcs)) == len(srcs)
    with pytest.raises(ValueError, match="unknown property group"):
        stream_check("memory")


@pytest.mark.parametrize("model, reset", [("dog2", "subtract"), ("fsm", "zero")])
def test_each_group_names_its_properties(formal_point, model, reset):
    contract = _contract(formal_point, model, reset)
    for group, expected in GROUP_ASSERTS.items():
        props = StreamProperties(contract, 2, groups=(group,)).statements()
        asserts = {p.name for p in props if p.kind == "assert"}
        if group == "tail":
            expected = expected | {f"reset.{reset}"}
        assert asserts == expected, group
        # the group's statements in harnesses.py, the assumptions of the base and of the
        # shared bookkeeping (the watched word and scale) in their modules
        assert all(p.src.split(":")[0].endswith("rtl/stream/harnesses.py")
                   or (p.kind == "assume" and p.src.split(":")[0].endswith(
                       ("rtl/stream/harness_base.py", "rtl/stream/property_watch.py")))
                   for p in props)
        # sby names a failing statement by its line: one property per line
        assert len({p.src for p in props}) == len(props)
    covers = {p.name for p in StreamProperties(contract, 2).statements()
              if p.kind == "cover"}
    assert {"cover.spike_pos", "cover.saturate_high", "cover.clear_mid_frame",
            "cover.threshold_write_meets_read"} <= covers
    assert ("cover.spike_neg" in covers) == contract.signed


def test_depth_is_two_frames_plus_the_lag(formal_point):
    contract = _contract(formal_point)
    geo = StreamGeometry(contract, 2)
    for harness in (StreamProperties(contract, 2), StreamEquivalence(contract, 2)):
        assert harness.depth == 2 * geo.beats_per_frame + geo.lag + 2 == 25
        harness.statements()


def test_synthesis_is_chosen_per_group(formal_point):
    """smtbmc ``--syn`` where it measured faster (``SYNTHESISED_GROUPS``), never for a
    harness that states the ``state`` group, never in prove mode."""
    contract = _contract(formal_point)
    for group in PROPERTY_GROUPS:
        harness = StreamProperties(contract, 2, groups=(group,))
        expected = ("--syn",) if group in SYNTHESISED_GROUPS else ()
        assert harness.smtbmc_options("bmc") == harness.smtbmc_options("cover") == expected
        assert harness.smtbmc_options("prove") == ()
    assert "state" not in SYNTHESISED_GROUPS
    assert StreamProperties(contract, 2).smtbmc_options("bmc") == ()
    assert StreamEquivalence(contract, 2).smtbmc_options("bmc") == ()


@pytest.mark.parametrize("group", [g if g == "protocol" else pytest.param(
    g, marks=pytest.mark.slow) for g in PROPERTY_GROUPS])  # the rest: make formal, -m slow
def test_shipped_array_holds_to_the_bound(formal_point, tmp_path, group):
    harness = StreamProperties(_contract(formal_point), 2, groups=(group,))
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


@pytest.mark.parametrize("model, lanes, reset", [
    pytest.param("dog2", 2, "subtract", marks=pytest.mark.slow),  # 73 s; make formal too
    ("fsm", 1, "zero")])
def test_bounded_equivalence_with_the_parallel_array(formal_point, tmp_path, model,
                                                     lanes, reset):
    size = (3, 4) if lanes == 2 else (3, 3)
    harness = StreamEquivalence(_contract(formal_point, model, reset, size), lanes)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "PASS", result.log.read_text()[-2000:]


@pytest.mark.parametrize("mutation, check, broken", [
    ("stream.threshold_off_by_one", "tail", "fire.threshold_implies_spike"),
    ("stream.advance_during_stall", "protocol", "output.one_per_beat"),
    ("stream.swapped_lanes", "equivalence", "equivalence.spikes"),
])
def test_seeded_bug_gives_a_counterexample(formal_point, tmp_path, mutation, check,
                                           broken):
    factory = get_architecture("stream").formal[check]
    harness = factory(_contract(formal_point), mutation=mutation, lanes=2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "FAIL"
    props = harness.statements()
    failing = {property_at(props, loc).name for loc in result.failed}
    assert broken in failing
    assert result.trace is not None and result.trace.is_file()


@pytest.mark.parametrize("mutation, check, broken", [
    # the accumulator memories start with any contents (power_up_memories): a clear
    # that misses a bank fails in the first frame, within the shipped bound
    ("stream.clear_forgets_scale0", "state", "state.fresh_after_clear"),
    ("stream.no_threshold_forwarding", "thresholds", "threshold.read_stage"),
])
def test_seeded_memory_bug_gives_a_counterexample(formal_point, tmp_path, mutation,
                                                  check, broken):
    factory = get_architecture("stream").formal[check]
    harness = factory(_contract(formal_point), mutation=mutation, lanes=2)
    result = run_sby(harness, tmp_path, mode="bmc", depth=harness.depth)
    assert result.status == "FAIL"
    props = harness.statements()
    assert broken in {property_at(props, loc).name for loc in result.failed}


def test_accumulators_start_from_any_contents(formal_point, tmp_path):
    """The shipped array's state check drops the accumulator memories' initial values
    (every bank's), and nothing else's."""
    harness = StreamProperties(_contract(formal_point), 2, groups=("state",))
    scales = _contract(formal_point).num_scales
    assert run_sby(harness, tmp_path, mode="bmc", depth=1).passed
    design = (tmp_path / "formal" / "model" / "design.il").read_text()
    inits = {}   # module -> its memory's INIT parameter
    for module in design.split("\nmodule ")[1:]:
        found = re.search(r"cell \$mem_v2 .*?parameter \\INIT (\S+)", module, re.S)
        if found:
            inits[module.split()[0]] = found.group(1)
    acc = [init for name, init in inits.items() if ".acc_s" in name]
    thr = [init for name, init in inits.items() if ".thr_s" in name]
    assert len(acc) == len(thr) == scales
    assert all(re.fullmatch(r"\d+'x", init) for init in acc)
    assert not any("x" in init for init in thr)
