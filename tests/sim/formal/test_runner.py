"""run_checks and its report: a seeded bug gives a readable counterexample (the property's
name and source line, the failing step, a VCD kept in the output folder that parses);
statuses and exit statuses for a pass, an unreached cover and a tool failure."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.sim.formal import runner as report_module
from rvsm.sim.formal.runner import run_checks

BUG = "parallel.threshold_off_by_one"


def parse_vcd(path: Path) -> tuple[set[str], list[int]]:
    """The variable names and the time stamps of a VCD file (ValueError if malformed)."""
    text = path.read_text()
    head, sep, body = text.partition("$enddefinitions")
    if not sep:
        raise ValueError("no $enddefinitions")
    names = set(re.findall(r"\$var\s+\S+\s+\d+\s+\S+\s+(\S+)", head))
    times = [int(t) for t in re.findall(r"^#(\d+)", body, flags=re.M)]
    if not names or times != sorted(times):
        raise ValueError("no variables or unordered time stamps")
    return names, times


def test_seeded_bug_gives_a_readable_counterexample(formal_point, tmp_path):
    report = run_checks(formal_point.contract(), "parallel", {}, mode="bmc", depth=4,
                        mutation=BUG, workdir=tmp_path)
    assert not report.ok and report.exit_status == 1
    (result,) = report.results
    assert (result.check, result.mode, result.depth, result.status) == \
        ("properties", "bmc", 4, "fail")
    cex = result.counterexample
    failed = {p.name for p in result.properties if p.status == "failed"}
    assert cex.property in failed and "fire.threshold_implies_spike" in failed
    # the source line is the statement of that property in the harness
    path, line = cex.src.rsplit(":", 1)
    assert path.endswith("rtl/parallel/harnesses.py")
    stated = Path(path).read_text().splitlines()[int(line) - 1]
    assert f'"{cex.property}"' in stated
    assert cex.description
    # cycle 0 is the reset state; the first strobed step is checked at cycle 1
    assert cex.step == 1
    assert cex.vcd.parent == tmp_path and cex.vcd.is_file()
    names, times = parse_vcd(cex.vcd)
    assert any("spike_pos" in n for n in names) and len(times) >= cex.step + 1
    held = {p.status for p in result.properties if p.name not in failed}
    assert held == {"passed to depth 2"}  # steps 0 and 1
    assert json.loads(json.dumps(report.to_json()))["checks"][0]["counterexample"][
        "property"] == cex.property


def test_bounded_pass_and_unreached_cover(formal_point, tmp_path):
    contract = formal_point.contract()
    passed = run_checks(contract, "parallel", {}, mode="bmc", depth=3,
                        workdir=tmp_path / "bmc")
    assert passed.ok and passed.exit_status == 0
    assert {p.status for p in passed.results[0].properties} == {"passed to depth 3"}
    assert all(p.kind == "assert" for p in passed.results[0].properties)
    covers = run_checks(contract, "parallel", {}, mode="cover", depth=1,
                        workdir=tmp_path / "cover")
    assert covers.exit_status == 1 and covers.results[0].status == "fail"
    statuses = {p.name: p.status for p in covers.results[0].properties}
    assert statuses["cover.saturate_low"] == "not covered"
    assert set(statuses.values()) <= {"covered", "not covered"}


def test_a_tool_failure_is_exit_status_3(formal_point, tmp_path, monkeypatch):
    def crash(*args, **kwargs):
        raise ToolError("yowasp-sby bmc ended without a verdict (exit -11)")

    monkeypatch.setattr(report_module, "run_sby", crash)
    report = run_checks(formal_point.contract(), "parallel", {}, workdir=tmp_path)
    (result,) = report.results
    assert result.status == "error" and "without a verdict" in result.message
    assert report.exit_status == 3 and not report.ok
    assert {p.status for p in result.properties} == {"not checked"}


def test_bad_requests_are_input_errors(formal_point, tmp_path):
    contract = formal_point.contract()
    with pytest.raises(RvsmError, match="unknown formal check 'nope'"):
        run_checks(contract, "parallel", {}, checks=["nope"], workdir=tmp_path)
    with pytest.raises(RvsmError, match="mode"):
        run_checks(contract, "parallel", {}, mode="sim", workdir=tmp_path)
    with pytest.raises(RvsmError, match="depth"):
        run_checks(contract, "parallel", {}, depth=0, workdir=tmp_path)
    with pytest.raises(RvsmError, match="mutation"):
        run_checks(contract, "parallel", {}, mutation="stream.nothing", workdir=tmp_path)


def test_shared_thresholds_formal(formal_point, tmp_path):
    """threshold.storage = "shared": the parallel array's properties hold (the threshold
    a scale's register, reset to the nominal one); the stream's check about its
    threshold memories does not apply and says so."""
    import dataclasses

    from rvsm.rtl.stream.architecture import STREAM

    shared = dataclasses.replace(formal_point, threshold_storage="shared").contract()
    report = run_checks(shared, "parallel", {}, workdir=tmp_path / "parallel")
    assert report.ok, [r.message for r in report.results]
    assert STREAM.formal_skip_reason("thresholds", shared)
    assert STREAM.formal_skip_reason("thresholds", formal_point.contract()) is None
    assert STREAM.formal_skip_reason("tail", shared) is None
    with pytest.raises(RvsmError, match="does not apply"):
        run_checks(shared, "stream", {"lanes": 1}, checks=["thresholds"], workdir=tmp_path)
