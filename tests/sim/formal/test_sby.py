"""The sby flow proves a true property, finds a counterexample for a false one, and
reaches a cover (a tiny counter, about a second per run)."""

from __future__ import annotations

import pytest
from amaranth.asserts import AnySeq
from amaranth.hdl import Assert, Cover, Elaboratable, Module, Mux, Signal

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.formal.sby import run_sby


class WrappingCounter(Elaboratable):
    """Counts enabled cycles and wraps at ``wrap``; asserts it stays at most 10."""

    def __init__(self, wrap: int) -> None:
        self.wrap = wrap

    def elaborate(self, platform):
        m = Module()
        count = Signal(4)
        enable = AnySeq(1)
        with m.If(enable):
            with m.If(count == self.wrap):
                m.d.sync += count.eq(0)
            with m.Else():
                m.d.sync += count.eq(count + 1)
        m.d.comb += Assert(count <= 10, "count stays at most 10")
        m.d.comb += Cover(count == 10)
        return m


def test_true_property_is_proven(tmp_path):
    result = run_sby(WrappingCounter(10), tmp_path, mode="prove", depth=12)
    assert result.status == "PASS" and result.passed and result.failed == ()


def test_false_property_gives_a_counterexample_trace(tmp_path):
    result = run_sby(WrappingCounter(15), tmp_path, mode="bmc", depth=15)
    assert result.status == "FAIL"
    assert result.failed and result.failed[0].endswith(f"test_sby.py:{_assert_line()}")
    assert result.trace is not None and result.trace.read_text().startswith("$")


def test_synthesised_model_gives_the_same_verdicts(tmp_path):
    """``--syn`` (yosys synthesises the model first): the same pass, the same failing
    line and a trace that still names the design's signals."""
    assert run_sby(WrappingCounter(10), tmp_path / "true", mode="bmc", depth=12,
                   engine_options=("--syn",)).passed
    result = run_sby(WrappingCounter(15), tmp_path / "false", mode="bmc", depth=15,
                     engine_options=("--syn",))
    assert "smtbmc --syn yices" in (tmp_path / "false" / "formal.sby").read_text()
    assert result.status == "FAIL"
    assert result.failed[0].endswith(f"test_sby.py:{_assert_line()}")
    assert result.trace is not None and "count" in result.trace.read_text()


def test_cover_is_reached(tmp_path):
    result = run_sby(WrappingCounter(10), tmp_path, mode="cover", depth=12)
    assert result.status == "PASS" and result.trace is not None


def test_bad_mode_and_depth_are_input_errors(tmp_path):
    with pytest.raises(RvsmError, match="mode"):
        run_sby(WrappingCounter(10), tmp_path, mode="sim")
    with pytest.raises(RvsmError, match="depth"):
        run_sby(WrappingCounter(10), tmp_path, depth=0)


def _assert_line() -> int:
    import inspect
    lines, start = inspect.getsourcelines(WrappingCounter.elaborate)
    return start + next(i for i, line in enumerate(lines) if "Assert(" in line)


def test_harness_names_the_failing_property(tmp_path):
    from rvsm.rtl.formal_harness import FormalHarness, property_at

    class Harness(FormalHarness):
        def __init__(self, wrap):
            super().__init__()
            self.wrap = wrap

        def elaborate(self, platform):
            m = Module()
            count = Signal(4)
            with m.If(AnySeq(1)):
                m.d.sync += count.eq(Mux(count == self.wrap, 0, count + 1))
            self.check(m, "count.bounded", count <= 10, "count stays at most 10")
            self.check(m, "count.reaches_ten", count == 10, "ten is reachable", "cover")
            return m

    good, bad = Harness(10), Harness(15)
    assert [p.name for p in good.statements()] == ["count.bounded", "count.reaches_ten"]
    result = run_sby(bad, tmp_path, mode="bmc", depth=15)
    assert result.status == "FAIL"
    props = bad.statements()
    assert property_at(props, result.failed[0]).name == "count.bounded"
    assert run_sby(good, tmp_path / "good", mode="prove", depth=12).passed
