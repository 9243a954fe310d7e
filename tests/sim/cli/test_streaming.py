"""CLI: simulate to .h5 (streamed), evaluate .h5, engines, .dat streaming."""

import json

import numpy as np

from rvsm.model.sensors.files import load_any_spikes
from rvsm.model.spikes.npz import load_spikes
from rvsm.sim.cli import main

SMALL = ["--size", "24x32", "--frames", "4", "--steps-per-frame", "8"]


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_h5_and_npz_hold_the_same_spikes_and_scores(tmp_path, capsys):
    h5, npz = tmp_path / "s.h5", tmp_path / "s.npz"
    common = ["simulate", "coin", *SMALL, "--model", "dog3", "--noise", "--seed", "2"]
    assert _run(capsys, *common, "-o", h5, "--chunk-steps", "5")[0] == 0
    assert _run(capsys, *common, "-o", npz, "--engine", "numpy", "--threads", "1")[0] == 0
    a, meta_a = load_any_spikes(h5)
    b, meta_b = load_spikes(npz)
    np.testing.assert_array_equal(a, b)
    assert meta_b.pop("versions")["rvsm"]  # both kinds record the versions (docs/cli.md)
    assert meta_a.pop("versions")["numpy"]
    assert meta_a == meta_b
    scores = [json.loads(_run(capsys, "evaluate", p, "--json")[1]) for p in (h5, npz)]
    assert scores[0] == scores[1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.h5", "s.npz"]


def test_fixed_point_to_h5(tmp_path, capsys):
    point = tmp_path / "p.toml"
    assert _run(capsys, "config", "new", "-o", point)[0] == 0
    out = tmp_path / "f.h5"
    code, text, err = _run(capsys, "simulate", "flyball", *SMALL, "--fixed", point,
                           "-o", out)
    assert code == 0, err
    spikes, meta = load_any_spikes(out)
    assert spikes.shape == (24, 4, 24, 32) and meta["kind"] == "fixed"
    assert f"{np.count_nonzero(spikes)} spikes" in text


def test_dat_streams_through_h5(tmp_path, capsys):
    h5, dat, back = tmp_path / "f.h5", tmp_path / "f.dat", tmp_path / "back.h5"
    assert _run(capsys, "simulate", "character", *SMALL, "--model", "fsm", "-o", h5,
                "--dat", dat, "--flip")[0] == 0
    again = tmp_path / "again.dat"
    assert _run(capsys, "dat", "export", h5, "-o", again, "--flip")[0] == 0
    assert again.read_bytes() == dat.read_bytes()
    assert _run(capsys, "dat", "import", dat, "--size", "24x32", "--flip", "-o", back)[0] == 0
    np.testing.assert_array_equal(load_any_spikes(back)[0], load_any_spikes(h5)[0])


def test_bad_output_suffix_and_threads(tmp_path, capsys):
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "-o", tmp_path / "x.txt")
    assert code == 2 and ".h5 or .npz" in err
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "--threads", "0",
                        "-o", tmp_path / "x.h5")
    assert code == 2 and "--threads" in err
    assert list(tmp_path.iterdir()) == []
