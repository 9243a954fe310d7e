"""Scenes checked before scoring (issue 33, finding 4): a spike file's meta keeps the
scene's absolute path and content digest; ``rvsm evaluate`` (and ``rvsm events export``,
which regenerates the references from the scene) refuse another scene unless ``--force``,
and a stored scene that is gone is met with a suggestion to pass SCENE."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rvsm.model.scene.digest import scene_digest
from rvsm.model.sensors.files import open_spikes
from rvsm.sim.cli import main


@pytest.fixture
def made(tmp_path, monkeypatch):
    """``a/scene.npy`` and ``a/s.h5`` simulated from it by a relative path, in ``a``."""
    a = tmp_path / "a"
    a.mkdir()
    frames = np.random.default_rng(3).uniform(0, 255, (4, 12, 16))
    np.save(a / "scene.npy", frames)
    np.save(a / "reversed.npy", frames[::-1])
    monkeypatch.chdir(a)
    assert main(["simulate", "scene.npy", "--model", "fsm", "--engine", "numpy",
                 "-o", "s.h5"]) == 0
    assert main(["simulate", "scene.npy", "--sensor", "dvs", "--model", "dog2",
                 "--engine", "numpy", "-o", "e.h5"]) == 0
    b = tmp_path / "b"
    b.mkdir()
    monkeypatch.chdir(b)
    return a


def test_meta_keeps_the_absolute_path_and_the_digest(made):
    with open_spikes(made / "s.h5") as src:
        meta = src.meta
    assert meta["scene_arg"] == str(made / "scene.npy")
    assert meta["scene_digest"] == scene_digest(made / "scene.npy")
    with open_spikes(made / "e.h5") as src:
        assert src.meta["scene_digest"] == scene_digest(made / "scene.npy")


def test_evaluate_from_another_folder_finds_the_scene(made, capsys):
    capsys.readouterr()
    assert main(["evaluate", str(made / "s.h5"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["psnr"] > 5


def test_another_scene_is_refused_naming_both_digests_unless_forced(made, capsys):
    capsys.readouterr()
    for argv in (["evaluate", str(made / "s.h5"), str(made / "reversed.npy")],
                 ["evaluate", str(made / "e.h5"), str(made / "reversed.npy")],
                 ["events", "export", str(made / "e.h5"), "--scene",
                  str(made / "reversed.npy"), "-o", "l.h5"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1
        assert scene_digest(made / "scene.npy") in err
        assert scene_digest(made / "reversed.npy") in err and "--force" in err
    assert not list(made.parent.joinpath("b").iterdir())
    assert main(["evaluate", str(made / "s.h5"), str(made / "reversed.npy"), "--force"]) == 0
    assert main(["evaluate", str(made / "s.h5"), str(made / "scene.npy")]) == 0  # the same


def test_a_built_in_scene_is_checked_by_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "coin", "--size", "12x16", "--frames", "3", "--model", "fsm",
                 "--engine", "numpy", "-o", "s.h5"]) == 0
    capsys.readouterr()
    assert main(["evaluate", "s.h5", "flyball"]) == 2
    assert "builtin:coin" in capsys.readouterr().err
    assert main(["evaluate", "s.h5"]) == 0


def test_a_stored_scene_that_is_gone_suggests_scene(made, capsys):
    (made / "scene.npy").rename(made / "moved.npy")
    capsys.readouterr()
    assert main(["evaluate", str(made / "s.h5")]) == 2
    err = capsys.readouterr().err
    assert "no longer exists" in err and "SCENE" in err and str(made / "scene.npy") in err
    assert main(["evaluate", str(made / "s.h5"), str(made / "moved.npy")]) == 0


def test_a_16_bit_scene_is_announced(tmp_path, monkeypatch, capsys):
    import imageio.v3 as iio

    monkeypatch.chdir(tmp_path)
    (tmp_path / "frames").mkdir()
    for i in range(2):
        iio.imwrite(tmp_path / "frames" / f"{i}.png", np.full((8, 8), 40000 + i, np.uint16))
    assert main(["simulate", "frames", "--model", "fsm", "--engine", "numpy",
                 "-o", "s.npz"]) == 0
    err = capsys.readouterr().err
    assert "rvsm: note: frames: 16-bit images, read at full precision" in err
