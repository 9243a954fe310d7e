"""End-to-end CLI: simulate -> evaluate, .dat conversion, and every bad-input path."""

import json

import numpy as np
import pytest

from rvsm.sim.cli import main

SMALL = ["--size", "24x32", "--frames", "4", "--steps-per-frame", "8"]


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_simulate_then_evaluate_json(tmp_path, capsys):
    spikes = tmp_path / "s.npz"
    code, out, err = _run(capsys, "simulate", "coin", *SMALL, "--model", "gauss2",
                          "--noise", "--seed", "3", "-o", spikes)
    assert code == 0, err
    assert "24x32" in out
    code, out, err = _run(capsys, "evaluate", spikes, "--json")
    assert code == 0, err
    result = json.loads(out)
    assert {"mse", "psnr", "ssim"} <= set(result)
    assert 5 < result["psnr"] < 60 and 0 < result["ssim"] <= 1
    from rvsm.model.spikes.npz import load_spikes

    data, meta = load_spikes(spikes)
    assert data.shape == (24, 2, 24, 32)
    assert meta["noise"]["seed"] == 3 and meta["model"] == "gauss2"


def test_simulate_is_reproducible(tmp_path, capsys):
    for name in ("a.npz", "b.npz"):
        assert _run(capsys, "simulate", "flyball", *SMALL, "--model", "dog3", "--noise",
                    "-o", tmp_path / name)[0] == 0
    from rvsm.model.spikes.npz import load_spikes

    np.testing.assert_array_equal(load_spikes(tmp_path / "a.npz")[0],
                                  load_spikes(tmp_path / "b.npz")[0])


def test_dat_export_import_round_trip(tmp_path, capsys):
    npz, dat, back = tmp_path / "f.npz", tmp_path / "f.dat", tmp_path / "back.npz"
    assert _run(capsys, "simulate", "character", *SMALL, "--model", "fsm", "-o", npz,
                "--dat", dat)[0] == 0
    assert _run(capsys, "dat", "import", dat, "--size", "24x32", "-o", back)[0] == 0
    from rvsm.model.spikes.npz import load_spikes

    np.testing.assert_array_equal(load_spikes(npz)[0], load_spikes(back)[0])


def _write_npy(path, array):
    np.save(path, array)
    return path


@pytest.mark.parametrize("case", [
    "unknown_model", "bad_phi", "zero_phi", "missing_path", "nan", "negative", "four_d",
    "k_without_noise", "bad_scale_phi", "bad_size",
])
def test_bad_input_one_line_nonzero_no_output(tmp_path, capsys, case):
    out_file = tmp_path / "out.npz"
    scene = "coin"
    extra = []
    if case == "unknown_model":
        extra = ["--model", "dog7"]
    elif case == "bad_phi":
        extra = ["--phi", "-5"]
    elif case == "zero_phi":
        extra = ["--phi", "0"]
    elif case == "missing_path":
        scene = str(tmp_path / "nope.npy")
    elif case == "nan":
        scene = str(_write_npy(tmp_path / "nan.npy", np.full((3, 8, 8), np.nan)))
    elif case == "negative":
        scene = str(_write_npy(tmp_path / "neg.npy", -np.ones((3, 8, 8))))
    elif case == "four_d":
        scene = str(_write_npy(tmp_path / "4d.npy", np.ones((3, 8, 8, 3))))
    elif case == "k_without_noise":
        extra = ["--k", "2"]
    elif case == "bad_scale_phi":
        extra = ["--model", "dog2", "--scale-phi", "400,abc"]
    elif case == "bad_size":
        extra = ["--size", "big"]
    args = ["simulate", scene, "--frames", "3", "--steps-per-frame", "2", *extra, "-o", out_file]
    if case != "bad_size" and not scene.endswith(".npy"):
        args[2:2] = ["--size", "16x16"]
    code, out, err = _run(capsys, *args)
    assert code == 2
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("rvsm: error: "), err
    assert "Traceback" not in err
    assert list(tmp_path.glob("out*")) == [] and list(tmp_path.glob(".out*")) == []


def test_truncated_dat_and_spike_files(tmp_path, capsys):
    (tmp_path / "t.dat").write_bytes(bytes(13))
    code, _, err = _run(capsys, "dat", "import", tmp_path / "t.dat", "--size", "4x8",
                        "-o", tmp_path / "o.npz")
    assert code == 2 and "truncated" in err and not (tmp_path / "o.npz").exists()
    (tmp_path / "bad.npz").write_bytes(b"PK\x03\x04 not really a zip")
    code, _, err = _run(capsys, "evaluate", tmp_path / "bad.npz")
    assert code == 2 and err.count("\n") == 1


def test_existing_output_survives_a_failed_run(tmp_path, capsys):
    target = tmp_path / "keep.npz"
    assert _run(capsys, "simulate", "coin", *SMALL, "--model", "fsm", "-o", target)[0] == 0
    before = target.read_bytes()
    code, _, _ = _run(capsys, "simulate", "coin", *SMALL, "--model", "nope", "-o", target)
    assert code == 2 and target.read_bytes() == before


def test_output_files_get_a_normal_mode(tmp_path, capsys):
    target = tmp_path / "m.npz"
    assert _run(capsys, "simulate", "coin", *SMALL, "--model", "fsm", "-o", target)[0] == 0
    assert target.stat().st_mode & 0o044  # readable by group/others under a usual umask


def test_simulate_fixed_then_evaluate(tmp_path, capsys):
    point = tmp_path / "p.toml"
    assert _run(capsys, "config", "new", "-o", point)[0] == 0
    spikes = tmp_path / "fx.npz"
    code, out, err = _run(capsys, "simulate", "coin", *SMALL, "--fixed", point, "-o", spikes)
    assert code == 0, err
    from rvsm.model.spikes.npz import load_spikes

    data, meta = load_spikes(spikes)
    assert data.shape == (24, 4, 24, 32) and meta["kind"] == "fixed"
    assert (meta["height"], meta["width"]) == (24, 32)
    code, out, err = _run(capsys, "evaluate", spikes, "--json")
    assert code == 0, err
    assert json.loads(out)["psnr"] > 10


def test_simulate_fixed_refuses_float_options(tmp_path, capsys):
    point = tmp_path / "p.toml"
    assert _run(capsys, "config", "new", "-o", point)[0] == 0
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "--fixed", point, "--model", "fsm",
                        "-o", tmp_path / "x.npz")
    assert code == 2 and "--model" in err and "design point" in err
    assert not (tmp_path / "x.npz").exists()


def test_evaluate_refuses_spikes_that_do_not_fit_the_scene(tmp_path, capsys):
    from rvsm.model.spikes.npz import save_spikes

    meta = {"scene_arg": "coin", "height": 16, "width": 16, "num_frames": 3,
            "steps_per_frame": 2, "hold": False, "model": "fsm", "phis": [400.0]}
    save_spikes(tmp_path / "mm.npz", np.zeros((5, 1, 8, 8), np.int8), meta)
    code, _, err = _run(capsys, "evaluate", tmp_path / "mm.npz")
    assert code == 2 and err.count("\n") == 1 and "do not match scene" in err
