"""``rvsm verilog``, ``verify`` and ``fpga`` take their build settings from the design
point's ``[rtl]`` table when the flag is not given; an explicit flag wins."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import design_point_toml
from rvsm.sim.cli import main


def _point(tmp_path: Path, table: str, size: tuple[int, int] = (8, 8),
           model: str = "dog4") -> str:
    point = replace(default_design_point().with_size(*size), model=model)
    path = tmp_path / "p.toml"
    path.write_text(design_point_toml(point) + "\n[rtl]\n" + table)
    return str(path)


class _FakeReport:
    def to_json(self) -> str:
        return json.dumps({"mode": "synthesis-only"})

    def table(self) -> str:
        return "report"


@pytest.fixture
def fpga_calls(monkeypatch: pytest.MonkeyPatch) -> list[dict]:
    """``rvsm fpga`` with the flow replaced: the keywords it was called with."""
    calls: list[dict] = []

    def fake(point, out, **kw):  # noqa: ANN001, ANN003, ANN202
        calls.append(kw)
        return _FakeReport()

    monkeypatch.setattr("rvsm.rtl.fpga.fpga_run.run_fpga", fake)
    return calls


def test_fpga_takes_the_point_settings(tmp_path: Path, capsys: pytest.CaptureFixture,
                                       fpga_calls: list[dict]) -> None:
    point = _point(tmp_path, 'lanes = 4\nfreq_mhz = 80\ndevice = "ecp5-45"\n'
                   'memory = "inferred"\n')
    assert main(["fpga", point, "--json", "-o", str(tmp_path / "w")]) == 0
    out, err = capsys.readouterr()
    kw = fpga_calls[-1]
    assert (kw["lanes"], kw["target_mhz"], kw["device"], kw["memory"]) == (
        4, 80.0, "ecp5-45", "inferred")
    assert err.splitlines() == [f"rvsm fpga: lanes 4, freq 80 MHz, device ecp5-45, memory "
                                f"inferred from {point} [rtl]"]
    settings = json.loads(out)["settings"]
    assert settings == {"arch": "stream", "interface": "native", "lanes": 4,
                        "fifo_depth": None, "freq_mhz": 80.0, "device": "ecp5-45",
                        "memory": "inferred", "point": point,
                        "from_point": ["lanes", "freq_mhz", "device", "memory"]}


def test_fpga_board_takes_the_point_package(tmp_path: Path, capsys: pytest.CaptureFixture,
                                           fpga_calls: list[dict]) -> None:
    point = _point(tmp_path, 'freq_mhz = 100\ndevice = "ecp5-85"\npackage = "CABGA756"\n')
    out_dir = ["-o", str(tmp_path / "w")]
    assert main(["fpga", point, "--board", "--json", *out_dir]) == 0
    out, err = capsys.readouterr()
    assert fpga_calls[-1]["board"] is True and fpga_calls[-1]["package"] == "CABGA756"
    assert err == (f"rvsm fpga: freq 100 MHz, device ecp5-85, package CABGA756 from {point} "
                   "[rtl]\n")
    settings = json.loads(out)["settings"]
    assert settings["package"] == "CABGA756" and "package" in settings["from_point"]
    assert main(["fpga", point, "--board", "--package", "CABGA554", *out_dir]) == 0
    assert fpga_calls[-1]["package"] == "CABGA554"  # the flag wins
    assert "package" not in capsys.readouterr().err
    assert main(["fpga", point, *out_dir]) == 0  # no board: no pins planned, no package
    assert "package" not in fpga_calls[-1] and "package" not in capsys.readouterr().err


def test_fpga_flag_wins_and_defaults_stay(tmp_path: Path, capsys: pytest.CaptureFixture,
                                          fpga_calls: list[dict]) -> None:
    point = _point(tmp_path, "lanes = 4\nfreq_mhz = 80\n")
    assert main(["fpga", point, "--lanes", "2", "--freq", "60", "--json", "-o",
                 str(tmp_path / "w")]) == 0
    out, err = capsys.readouterr()
    kw = fpga_calls[-1]
    assert (kw["lanes"], kw["target_mhz"], kw["device"], kw["memory"]) == (
        2, 60.0, "ecp5-85", "dp16kd")  # flags, then today's defaults
    assert err == ""  # nothing came from the point
    assert json.loads(out)["settings"]["from_point"] == []
    plain = _point(tmp_path, "")  # an empty table: today's defaults
    assert main(["fpga", plain, "-o", str(tmp_path / "w")]) == 0
    kw = fpga_calls[-1]
    assert (kw["lanes"], kw["target_mhz"], kw["arch"].name) == (1, 125.0, "stream")


def test_a_point_option_the_chosen_architecture_lacks_is_not_used(
        tmp_path: Path, capsys: pytest.CaptureFixture, fpga_calls: list[dict]) -> None:
    point = _point(tmp_path, "lanes = 4\n", size=(2, 2), model="fsm")
    assert main(["fpga", point, "--arch", "parallel", "-o", str(tmp_path / "w")]) == 0
    assert fpga_calls[-1]["lanes"] is None
    assert capsys.readouterr().err == ("rvsm fpga: rtl.lanes not used (arch parallel, "
                                       "interface native does not take it)\n")


@pytest.mark.parametrize("command", ["verilog", "verify", "fpga"])
def test_a_bad_value_is_refused_with_exit_2_and_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture, command: str) -> None:
    point = _point(tmp_path, 'device = "xc7a35t"\n')
    argv = {"verilog": ["verilog", point, "-o", str(tmp_path / "v")],
            "verify": ["verify", "coin", "--fixed", point, "--work", str(tmp_path / "w")],
            "fpga": ["fpga", point, "-o", str(tmp_path / "f")]}[command]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err == (f"rvsm: error: {point}: rtl.device = 'xc7a35t' is not valid; choose one "
                   "of ecp5-25, ecp5-45, ecp5-85, ice40-hx1k, ice40-hx8k, ice40-up5k, gw1n-1, "
                   "gw1n-4, gw1n-9, gw2a-18, gw5a-25, gw5ast-138, ccgm1a1\n")
    assert not (tmp_path / "v").exists() and not (tmp_path / "f").exists()


def test_verilog_honours_the_point_lanes_and_clock(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    point = _point(tmp_path, "lanes = 4\nfreq_mhz = 80\n")
    assert main(["verilog", point, "-o", str(tmp_path / "a")]) == 0
    out, err = capsys.readouterr()
    assert f"rvsm verilog: lanes 4, freq 80 MHz from {point} [rtl]" in err
    assert "architecture stream (lanes 4)" in out
    ports = json.loads((tmp_path / "a" / "rvsm_stream_array.ports.json").read_text())
    assert ports["timing"]["lanes"] == 4
    assert "-period 12.500" in (tmp_path / "a" / "rvsm_stream_array.sdc").read_text()
    assert main(["verilog", point, "-o", str(tmp_path / "b"), "--lanes", "2",
                 "--clock-mhz", "50"]) == 0  # the flags win
    ports = json.loads((tmp_path / "b" / "rvsm_stream_array.ports.json").read_text())
    assert ports["timing"]["lanes"] == 2
    assert "-period 20.000" in (tmp_path / "b" / "rvsm_stream_array.sdc").read_text()
    assert "from" not in capsys.readouterr().err


def test_verify_honours_the_point_lanes(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    point = _point(tmp_path, "lanes = 2\n", size=(4, 4), model="dog1")
    assert main(["verify", "--random", "1", "--fixed", point, "--size", "4x4", "--steps",
                 "16", "--json", "--work", str(tmp_path / "w")]) == 0
    out, err = capsys.readouterr()
    r = json.loads(out)
    assert r["mismatches"] == 0 and r["options"] == {"lanes": 2}
    assert r["settings"]["lanes"] == 2 and r["settings"]["from_point"] == ["lanes"]
    assert f"rvsm verify: lanes 2 from {point} [rtl]" in err
    bad = _point(tmp_path, "lanes = 3\n", size=(4, 4), model="dog1")  # 3 does not divide 4
    assert main(["verify", "--random", "1", "--fixed", bad, "--size", "4x4", "--steps", "16",
                 "--work", str(tmp_path / "w")]) == 2
    assert "lanes" in capsys.readouterr().err


def test_config_check_names_the_settings_and_refuses_a_bad_name(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    point = _point(tmp_path, 'lanes = 4\ninterface = "axis"\nfifo_depth = 8\n')
    assert main(["config", "check", point]) == 0
    assert ("built with lanes = 4, interface = 'axis', fifo_depth = 8 ([rtl]"
            in capsys.readouterr().out)
    bad = _point(tmp_path, 'arch = "parallel"\ninterface = "axis"\n')
    assert main(["config", "check", bad]) == 2
    assert capsys.readouterr().err == (f"rvsm: error: {bad}: rtl.interface = 'axis' is not "
                                       "valid; arch parallel is offered with native\n")
    lacks = _point(tmp_path, 'device = "ecp5-45"\npackage = "CABGA756"\n')
    for argv in (["config", "check", lacks], ["fpga", lacks, "--board", "-o",
                                               str(tmp_path / "f")]):
        assert main(argv) == 2
        assert capsys.readouterr().err == (
            f"rvsm: error: {lacks}: rtl.package = 'CABGA756' is not valid; rtl.device "
            "ecp5-45 comes in CABGA381, CABGA554\n")
    assert main(["config", "new"]) == 0
    assert "\n# [rtl]\n# arch: " in capsys.readouterr().out
