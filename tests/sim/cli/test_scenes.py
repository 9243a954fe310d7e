"""``rvsm scenes``: the list and the contact sheet."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np

from rvsm.model.scene import library as lib
from rvsm.sim.cli import main


def test_scenes_cli(tmp_path, capsys) -> None:
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    assert all(n in out for n in lib.SCENE_NAMES) and "250x400" in out
    target = tmp_path / "sheet" / "coin.png"
    assert main(["scenes", "--render", "coin", "-o", str(target), "--size", "40x64"]) == 0
    img = iio.imread(target)
    assert img.shape[0] == 40 and img.dtype == np.uint8
    assert sorted(p.name for p in target.parent.iterdir()) == ["coin.png"]
    assert main(["scenes", "--render", "nope", "-o", str(target)]) == 2
    assert main(["scenes", "--render", "coin"]) == 2
    assert "rvsm: error:" in capsys.readouterr().err
