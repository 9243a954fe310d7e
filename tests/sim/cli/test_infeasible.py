"""Requests the device cannot meet exit 2 on one line naming the budget (issue 41, 5)."""

from __future__ import annotations

from pathlib import Path

from rvsm.sim.cli import main

POINT = (Path(__file__).parents[3] / "points" / "ecp5-85-40khz.toml").read_text()


def _point(tmp_path, **swap) -> str:
    text = POINT
    for old, new in swap.items():
        text = text.replace(old, new)
    f = tmp_path / "p.toml"
    f.write_text(text)
    return str(f)


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_unknown_device_is_one_line_with_the_choices(tmp_path, capsys):
    f = _point(tmp_path)
    assert main(["fpga", "--device", "ecp5-100", f, "-o", str(tmp_path / "o")]) == 2
    line = _one_line_error(capsys)
    assert "unknown FPGA device 'ecp5-100'; choose one of: ecp5-25" in line
    assert "gw5ast-138" in line  # the one device list


def test_fpga_refuses_an_estimate_only_device_in_one_line(tmp_path, capsys):
    f = _point(tmp_path)
    assert main(["fpga", "--device", "ice40-hx8k", f, "-o", str(tmp_path / "o")]) == 2
    line = _one_line_error(capsys)
    assert line.startswith("rvsm: error: ice40-hx8k is estimate only:")
    assert line.endswith("the devices that place and route: ecp5-25, ecp5-45, ecp5-85")
    assert not (tmp_path / "o").exists()


def test_an_estimate_only_rtl_device_is_refused_by_fpga_and_marked_by_config_check(
        tmp_path, capsys):
    f = _point(tmp_path, **{'device = "ecp5-85"\npackage = "CABGA756"':
                            'device = "gw5ast-138"'})
    assert main(["fpga", f, "-o", str(tmp_path / "o")]) == 2
    assert _one_line_error(capsys).startswith("rvsm: error: gw5ast-138 is estimate only:")
    assert main(["config", "check", f]) == 0
    out = capsys.readouterr().out
    assert "fits gw5ast-138: state" in out
    assert "(estimate only: rvsm fpga does not place gw5ast-138" in out


def test_config_check_names_accumulator_bits_and_shift(tmp_path, capsys):
    f = _point(tmp_path, **{"accumulator_bits = 14": "accumulator_bits = 8"})
    assert main(["config", "check", f]) == 2
    line = _one_line_error(capsys)
    assert "datapath.accumulator_bits = 8 holds shared thresholds up to 127" in line
    assert "6375 LSBs at datapath.shift = 4" in line
    assert "accumulator_bits = 14 (the smallest" in line and "datapath.shift = 10" in line


def test_config_check_judges_the_rtl_device(tmp_path, capsys):
    f = _point(tmp_path, **{'"dog2"': '"dog4"', '"shared"': '"per-pixel"'})
    assert main(["config", "check", f]) == 2
    line = _one_line_error(capsys)
    assert "needs 732 of the 208 DP16KD of rtl.device = ecp5-85 (252 % over)" in line
    f = _point(tmp_path, **{"freq_mhz = 100.0": "freq_mhz = 900.0"})
    assert main(["config", "check", f]) == 2
    assert "above the ecp5-85 Fmax model, 115.7 MHz" in _one_line_error(capsys)
    assert main(["config", "check", _point(tmp_path)]) == 0
    assert "fits ecp5-85 CABGA756: state 192 / 208 DP16KD" in capsys.readouterr().out


def test_datasheet_rate_the_clock_cannot_meet(tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["datasheet", _point(tmp_path), "-o", str(out), "--rate-hz", "400000"]) == 2
    line = _one_line_error(capsys)
    assert "fmax 1,000 / 116 MHz (+764 %)" in line and "--allow-infeasible" in line
    assert not out.exists()


def test_datasheet_judges_the_io_on_the_point_package(tmp_path, capsys):
    """Without ``[rtl] package`` the shipped point is judged on the ecp5-85's default
    CABGA381, whose transmit pairs do not carry its links: refused before any work."""
    out = tmp_path / "ds"
    bare = _point(tmp_path, **{'package = "CABGA756"\n': ""})
    assert main(["datasheet", bare, "-o", str(out)]) == 2
    line = _one_line_error(capsys)
    assert "io 22 / 17 true-LVDS transmit pairs" in line and "--allow-infeasible" in line
    assert not out.exists()
    lacks = _point(tmp_path, **{'package = "CABGA756"': 'package = "CABGA999"'})
    assert main(["datasheet", lacks, "-o", str(out)]) == 2
    assert "rtl.package = 'CABGA999' is not valid; rtl.device ecp5-85 comes in CABGA381, " \
        "CABGA554, CABGA756" in _one_line_error(capsys)


def test_verilog_warns_when_the_sdc_clock_passes_the_fmax_model(tmp_path, capsys):
    from rvsm.sim.cli.rtl import _warn_above_fmax

    point = _point(tmp_path)
    _warn_above_fmax(point, 900.0, 40, True)
    line = _one_line_error(capsys)
    assert line.startswith("rvsm verilog: warning: rtl.freq_mhz = 900 is above the ecp5-85")
    assert "the SDC asks for 900 MHz anyway" in line
    _warn_above_fmax(point, 300.0, 40, False)
    assert "--clock-mhz = 300" in _one_line_error(capsys)
    _warn_above_fmax(point, 100.0, 40, True)
    assert capsys.readouterr().err == ""
