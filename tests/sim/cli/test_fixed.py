"""``rvsm config new|check``, ``stimulus``, ``profile`` and ``cost``."""

from __future__ import annotations

import dataclasses
import json

from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.fixed.stimulus import load_stimulus
from rvsm.sim.cli import main

SIZE = (24, 32)


def _point(**kw) -> DesignPoint:
    return dataclasses.replace(default_design_point(), height=SIZE[0], width=SIZE[1], **kw)


def test_fixed_twin_commands(tmp_path, capsys):
    assert main(["config", "new"]) == 0
    text = capsys.readouterr().out
    assert "[datapath]" in text and "accumulator_bits = 18" in text
    point = tmp_path / "p.toml"
    assert main(["config", "new", "-o", str(point), "--size", "24x32"]) == 0
    assert main(["config", "check", str(point)]) == 0
    assert "101999" in capsys.readouterr().out
    common = ["character", "--fixed", str(point), "--frames", "4"]
    assert main(["stimulus", *common, "-o", str(tmp_path / "s.npz")]) == 0
    assert load_stimulus(tmp_path / "s.npz").check()
    assert main(["profile", *common, "--plot", str(tmp_path / "prof.png")]) == 0
    assert (tmp_path / "prof.png").stat().st_size > 1000
    capsys.readouterr()
    assert main(["cost", *common, "--size", "16x20", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["height"] == 16 and {"agreement", "psnr_float", "psnr_fixed", "psnr_cost"} <= set(
        out)
    bad = tmp_path / "bad.toml"
    save_design_point(bad, _point())
    bad.write_text(bad.read_text().replace('model = "dog4"', 'model = "dog9"'))
    assert main(["config", "check", str(bad)]) == 2
    assert "array.model" in capsys.readouterr().err
