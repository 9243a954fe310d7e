"""The one scene rule (:class:`rvsm.sim.cli.args.SceneRequest`), command by command.

A scene file is used at its own size unless ``--size`` is given (then it is centre-cropped,
and a ``--size`` larger than the file is refused naming ``--size``); a design point's size
follows the scene; ``rvsm evaluate`` shapes the scene as the spike file says it was made.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.fixed.stimulus import load_stimulus
from rvsm.model.spikes.npz import load_spikes
from rvsm.sim.cli import main

FILE_SIZE = (12, 20)
STEPPING = ["--steps-per-frame", "2"]


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _npy(path, shape):
    np.save(path, np.random.default_rng(0).uniform(16.0, 240.0, shape))
    return path


@pytest.fixture
def scene_file(tmp_path):
    """A 3-frame 12x20 ``.npy`` scene."""
    return _npy(tmp_path / "clip.npy", (3, *FILE_SIZE))


@pytest.fixture
def point(tmp_path):
    """The default design point (250x400): a scene file's size must win over it."""
    path = tmp_path / "p.toml"
    save_design_point(path, default_design_point())
    return path


def _simulate(capsys, tmp, scene, point, size):
    out = tmp / "float.npz"
    code, _, err = _run(capsys, "simulate", scene, *size, *STEPPING, "-o", out)
    return code, err, (load_spikes(out)[0].shape[2:] if code == 0 else None)


def _simulate_fixed(capsys, tmp, scene, point, size):
    out = tmp / "fixed.npz"
    code, _, err = _run(capsys, "simulate", scene, *size, *STEPPING, "--fixed", point,
                        "-o", out)
    return code, err, (load_spikes(out)[0].shape[2:] if code == 0 else None)


def _stimulus(capsys, tmp, scene, point, size):
    out = tmp / "stim.npz"
    code, _, err = _run(capsys, "stimulus", scene, *size, *STEPPING, "--fixed", point,
                        "-o", out)
    return code, err, (load_stimulus(out).spikes.shape[2:] if code == 0 else None)


def _cost(capsys, tmp, scene, point, size):
    code, out, err = _run(capsys, "cost", scene, *size, *STEPPING, "--fixed", point,
                          "--json")
    return code, err, ((json.loads(out)["height"], json.loads(out)["width"])
                       if code == 0 else None)


COMMANDS = {"simulate": _simulate, "simulate --fixed": _simulate_fixed,
            "stimulus": _stimulus, "cost": _cost}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize(("size", "expected"), [((), FILE_SIZE), (("--size", "8x16"), (8, 16))])
def test_a_scene_file_keeps_its_size_unless_size_is_given(command, size, expected, tmp_path,
                                                          capsys, scene_file, point):
    code, err, shape = COMMANDS[command](capsys, tmp_path, scene_file, point, size)
    assert code == 0, err
    assert tuple(shape) == expected


@pytest.mark.parametrize("command", COMMANDS)
def test_a_size_larger_than_the_file_is_refused_naming_size(command, tmp_path, capsys,
                                                             scene_file, point):
    code, err, _ = COMMANDS[command](capsys, tmp_path, scene_file, point, ("--size", "16x32"))
    assert code == 2 and err.count("\n") == 1
    assert "--size 12x20" in err


def test_a_builtin_scene_is_rendered_at_the_design_points_size(tmp_path, capsys):
    small = tmp_path / "small.toml"
    save_design_point(small, default_design_point().with_size(8, 12))
    code, err, shape = _stimulus(capsys, tmp_path, "coin", small, ("--frames", "2"))
    assert code == 0, err
    assert tuple(shape) == (8, 12)


def test_evaluate_shapes_the_scene_as_the_spikes_were_made(tmp_path, capsys, scene_file):
    spikes = tmp_path / "s.npz"
    assert _run(capsys, "simulate", scene_file, "--size", "8x16", *STEPPING, "--model", "fsm",
                "-o", spikes)[0] == 0
    for scene in ((), (scene_file,)):  # from the meta, or SCENE given again
        code, out, err = _run(capsys, "evaluate", spikes, *scene)
        assert code == 0, err
        assert "frames scored" in out
    code, _, err = _run(capsys, "evaluate", spikes, scene_file, "--size", "12x20")
    assert code == 2 and err.count("\n") == 1 and "--size 8x16" in err
    code, _, err = _run(capsys, "evaluate", spikes, "--steps-per-frame", "3")
    assert code == 2 and err.count("\n") == 1 and "--steps-per-frame" in err


def test_verify_shapes_the_scene_by_the_same_rule(tmp_path, capsys, scene_file, point,
                                                  monkeypatch):
    """``--steps-per-frame`` reaches the stimulus; the point follows the file's size."""
    import rvsm.sim.cosim.verify as verify_module

    seen = {}

    def check_stimulus(stim, *args, **kwargs):
        seen.update(steps=stim.num_steps, shape=stim.codes.shape[1:])
        return {"mismatches": 0}

    monkeypatch.setattr(verify_module, "check_stimulus", check_stimulus)
    code, _, err = _run(capsys, "verify", scene_file, "--fixed", point, "--arch", "parallel",
                        "--steps-per-frame", "3", "--json", "--work", tmp_path / "work")
    assert code == 0, err
    assert seen == {"steps": (3 - 1) * 3, "shape": FILE_SIZE}


def test_verify_refuses_what_the_rule_cannot_honour(tmp_path, capsys, point):
    big = _npy(tmp_path / "big.npy", (2, 70, 70))
    code, _, err = _run(capsys, "verify", big, "--fixed", point, "--arch", "parallel",
                        "--work", tmp_path / "work")
    assert code == 2 and err.count("\n") == 1 and "--size" in err
    code, _, err = _run(capsys, "verify", "--random", "1", "--fixed", point, "--size", "4x4",
                        "--steps", "10", "--hold", "--work", tmp_path / "work")
    assert code == 2 and err.count("\n") == 1 and "--hold" in err
