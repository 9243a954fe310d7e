"""The formal check of the IP's register file (``rvsm formal --arch stream --interface axis
--check registers``): registered, proven on the shipped register file for a per-pixel and
a shared-threshold tiny point (dog2 and dog4), every cover reached, and deliberately
broken register files give counterexamples naming the property they break: a field's
maximum judged on its width instead of its span (issue 34's bug: the counterexample is a
value that fits the field's bits but not its span), no maximum checked, the IP's refusal
ignored, reads of the reset values. A few seconds of solver time each."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
from amaranth.hdl import Const, Signal

import rvsm.rtl.ip.register_harness as register_harness
from rvsm.model.fixed.point_toml import load_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.ip.axi_lite import AxiLiteRegisters
from rvsm.rtl.ip.register_harness import RegisterFileProperties, ip_registers
from rvsm.rtl.ip.register_map import Register, RegisterMap
from rvsm.rtl.ip.register_model import RegisterFileModel
from rvsm.rtl.ip.wrapper import ip_regmap
from rvsm.sim.formal.runner import run_checks

DATA = Path(__file__).resolve().parents[2] / "data"
POINTS = {"per-pixel": DATA / "formal-tiny.toml", "shared": DATA / "formal-tiny-shared.toml"}
OPTIONS = {"lanes": 2, "fifo_depth": 16}
ASSERTS = {"write.response", "write.value", "write.pulse", "write.written", "read.response",
           "read.data", "axi.write_one_at_a_time", "axi.write_response_for_a_write",
           "axi.write_latency", "axi.write_response_held", "axi.read_one_at_a_time",
           "axi.read_response_for_a_read", "axi.read_latency", "axi.read_response_held",
           "invariant.write_channel", "invariant.write_payload", "invariant.read_channel"}
COVERS = {"cover.write_okay_changes", "cover.write_above_max", "cover.write_too_wide",
          "cover.write_refused", "cover.w1c_cleared", "cover.read_back",
          "cover.read_unmapped"}


def _contract(point: str, model: str = "dog2"):
    p = load_design_point(POINTS[point]).with_size(3, 4)
    return dataclasses.replace(p, model=model).contract()


def _run(tmp_path: Path, point: str, model: str = "dog2", mode: str | None = None):
    report = run_checks(_contract(point, model), get_architecture("stream", "axis"), OPTIONS,
                        checks=["registers"], mode=mode, workdir=tmp_path)
    (result,) = report.results
    return report, result


def test_registered_as_the_ip_check_with_one_name_per_line():
    arch = get_architecture("stream", "axis")
    assert set(arch.formal) == {"registers"}
    harness = arch.formal["registers"](_contract("per-pixel"), mutation=None, **OPTIONS)
    assert isinstance(harness, RegisterFileProperties) and harness.provable
    props = harness.statements()
    assert {p.name for p in props if p.kind == "assert"} == ASSERTS
    assert {p.name for p in props if p.kind == "cover"} == COVERS
    assert len({p.src for p in props}) == len(props)  # sby names a statement by its line
    assert all(p.src.split(":")[0].endswith("rtl/ip/register_harness.py") for p in props)
    # the map the harness checks is the IP's, whose maxima fill their fields' widths
    regmap = harness.regmap
    assert regmap == ip_regmap(_contract("per-pixel"), 2, 16)
    scale = regmap.field("THR_ADDR", "scale")
    assert scale.max == (1 << scale.width) - 1 < (1 << regmap["THR_ADDR"].span(scale)) - 1
    with pytest.raises(RvsmError, match="unknown mutation"):
        ip_registers(_contract("per-pixel"), mutation="stream.threshold_off_by_one")


@pytest.mark.parametrize("model", ["dog2", "dog4"])
@pytest.mark.parametrize("point", sorted(POINTS))
def test_the_shipped_register_file_is_proven(tmp_path, point, model):
    report, result = _run(tmp_path, point, model)
    assert report.exit_status == 0, result.message or result.log.read_text()[-2000:]
    assert (result.mode, result.depth) == ("prove", RegisterFileProperties.depth)
    assert {p.name: p.status for p in result.properties} == dict.fromkeys(ASSERTS, "proven")


@pytest.mark.parametrize("point", sorted(POINTS))
def test_every_cover_is_reached(tmp_path, point):
    report, result = _run(tmp_path, point, mode="cover")
    assert report.exit_status == 0, result.message
    assert {p.name: p.status for p in result.properties} == dict.fromkeys(COVERS, "covered")


@pytest.mark.parametrize("source, lanes", [("points/ecp5-85-40khz.toml", 4), ("default", 4)])
def test_full_size_register_maps_are_proven(tmp_path, source, lanes):
    """The check sees the array only through the register map, so the maps of full-size
    builds prove as fast (through the API: ``rvsm formal`` keeps its 64-pixel rule): the
    shipped ECP5 point (shared thresholds) and the default 250x400 dog4 point (per-pixel
    thresholds, three data chunks, a 15-bit THR_ADDR.word)."""
    from rvsm.model.fixed.design_point import default_design_point

    point = (default_design_point() if source == "default"
             else load_design_point(DATA.parents[1] / source))
    contract = point.contract()
    report = run_checks(contract, get_architecture("stream", "axis"),
                        {"lanes": lanes, "fifo_depth": 16}, checks=["registers"],
                        workdir=tmp_path)
    assert report.exit_status == 0 and report.results[0].mode == "prove"
    assert contract.height * contract.width == 250 * 400


def _final_values(vcd: Path, names: set[str]) -> dict[str, int]:
    """The last value of each of ``names``, signals of the VCD's top scope."""
    head, _, body = vcd.read_text().partition("$enddefinitions")
    ids, depth = {}, 0
    for token in re.finditer(r"\$scope|\$upscope|\$var\s+\S+\s+\d+\s+(\S+)\s+(\S+)", head):
        if token.group(0) == "$scope":
            depth += 1
        elif token.group(0) == "$upscope":
            depth -= 1
        elif depth == 1 and token.group(2) in names:
            ids[token.group(1)] = token.group(2)
    values = {}
    for bits, ident in re.findall(r"^b([01]+)\s+(\S+)", body, flags=re.M):
        if ident in ids:
            values[ids[ident]] = int(bits, 2)
    return values


class _WidthJudged(AxiLiteRegisters):
    """Issue 34's bug: each field's maximum judged on the field's own bits (a maximum
    that fills them is not checked at all), so a value too wide for the field is
    truncated into range instead of refused."""

    def elaborate(self, platform):
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(Register, "span", lambda self, field: field.width)
            return super().elaborate(platform)


def _no_max(regmap: RegisterMap) -> AxiLiteRegisters:
    """A register file that checks no field's maximum."""
    plain = tuple(dataclasses.replace(r, fields=tuple(dataclasses.replace(f, max=None)
                                                      for f in r.fields))
                  for r in regmap.registers)
    return AxiLiteRegisters(dataclasses.replace(regmap, registers=plain))


class _RefuseIgnored(AxiLiteRegisters):
    """Writes the IP refuses (a threshold commit while STATUS.init) answer OKAY."""

    def elaborate(self, platform):
        refuse, self.refuse = self.refuse, {k: Signal(name=f"{k}_ignored".lower())
                                            for k in self.refuse}
        try:
            return super().elaborate(platform)
        finally:
            self.refuse = refuse


class _ReadsResetValues(AxiLiteRegisters):
    """Every register reads its reset value (the read multiplexer wired to constants)."""

    def read_value(self, reg: str):
        return Const(self.regmap[reg].reset, 32)


@pytest.mark.parametrize("point", sorted(POINTS))
def test_a_maximum_judged_on_the_field_width_gives_a_counterexample(tmp_path, point,
                                                                     monkeypatch):
    monkeypatch.setattr(register_harness, "AxiLiteRegisters", _WidthJudged)
    report, result = _run(tmp_path, point)
    assert report.exit_status == 1 and result.status == "fail"
    cex = result.counterexample
    failed = {p.name for p in result.properties if p.status == "failed"}
    assert cex.property in failed and "write.response" in failed
    assert cex.step == 3  # the write's handshakes at step 0, bvalid at step 3
    # the counterexample is the span case: a value within the maximum in the field's
    # bits, above it on the field's span; the model answers SLVERR
    got = _final_values(cex.vcd, {"aw_addr", "w_data"})
    regmap = ip_regmap(_contract(point), 2, 16)
    model = RegisterFileModel(regmap)
    reg = model.register_at(got["aw_addr"])
    data = got["w_data"]
    assert reg is not None and reg.name == "THR_ADDR"
    assert any((data >> f.lsb) & ((1 << f.width) - 1) <= f.max
               < (data >> f.lsb) & ((1 << reg.span(f)) - 1)
               for f in reg.fields if f.max is not None)
    assert model.write(got["aw_addr"], data) == 2  # SLVERR


@pytest.mark.parametrize("broken, broken_property", [
    (_no_max, "write.response"),
    (_RefuseIgnored, "write.response"),
    (_ReadsResetValues, "read.data"),
])
def test_a_broken_register_file_gives_a_counterexample(tmp_path, monkeypatch, broken,
                                                       broken_property):
    monkeypatch.setattr(register_harness, "AxiLiteRegisters", broken)
    report, result = _run(tmp_path, "per-pixel")
    assert report.exit_status == 1 and result.status == "fail"
    failed = {p.name for p in result.properties if p.status == "failed"}
    assert broken_property in failed and result.counterexample.vcd.is_file()
