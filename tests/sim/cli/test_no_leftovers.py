"""No leftovers on any refusal (issue 33, finding 3): for every pair of outputs a command
writes, and for each command's refusals that come after its outputs were checked, a
refused run leaves the folder as it found it: no hidden ``.NAME.xxxx.partial.*`` file, no
half-written output, no folder it created."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from rvsm.sim.cli import main

SMALL = ["--frames", "3", "--engine", "numpy"]


def _listing(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> dict[str, Path]:
    """Input files the refused commands read, made once (outside the test folders)."""
    d = tmp_path_factory.mktemp("inputs")
    files = {"dog4": d / "dog4.h5", "fsm": d / "fsm.h5", "events": d / "events.h5",
             "point": d / "point.toml", "dvs_point": d / "dvs.toml", "list": d / "list.h5"}
    assert main(["simulate", "coin", "--size", "16x16", *SMALL, "--model", "dog4",
                 "-o", str(files["dog4"])]) == 0
    assert main(["simulate", "coin", "--size", "16x16", *SMALL, "--model", "fsm",
                 "-o", str(files["fsm"])]) == 0
    assert main(["simulate", "coin", "--size", "16x16", *SMALL, "--sensor", "dvs",
                 "--model", "dog2", "-o", str(files["events"])]) == 0
    assert main(["config", "new", "--size", "16x16", "-o", str(files["point"])]) == 0
    assert main(["config", "new", "--sensor", "dvs", "--size", "16x16",
                 "-o", str(files["dvs_point"])]) == 0
    assert main(["events", "export", str(files["events"]), "-o", str(files["list"])]) == 0
    files["dsec"] = d / "dsec.h5"  # two events of one pixel in one 25 us step
    with h5py.File(files["dsec"], "w") as f:
        f["events/t"] = np.array([0, 30, 40], np.uint32)
        f["events/x"], f["events/y"] = np.array([1, 2, 2], np.uint16), np.zeros(3, np.uint16)
        f["events/p"] = np.array([1, 0, 1], np.uint8)
    files["list_one"] = d / "one.h5"
    assert main(["events", "export", str(files["events"]), "--scale", "1",
                 "-o", str(files["list_one"])]) == 0
    files["reversed"] = d / "reversed.npy"
    np.save(files["reversed"], np.zeros((3, 16, 16)))
    return files


def _cases(i: dict[str, Path]) -> list[tuple[str, list[str]]]:
    """(name, argv) of refused runs; outputs are relative (the test runs in its folder)."""
    sim = ["simulate", "coin", *SMALL]
    return [
        # simulate -o X --dat Y: the .dat refuses the shape after -o was checked
        ("h5 + dat, H*W not a multiple of 8", [*sim, "--size", "31x45", "--model", "fsm",
                                               "-o", "s.h5", "--dat", "s.dat"]),
        ("npz + dat, H*W not a multiple of 8", [*sim, "--size", "31x45", "--model", "fsm",
                                                "-o", "s.npz", "--dat", "s.dat"]),
        ("h5 + dat, several scales", [*sim, "--size", "16x16", "--model", "dog4",
                                      "-o", "s.h5", "--dat", "s.dat"]),
        ("h5 + dat in a new folder", [*sim, "--size", "31x45", "--model", "fsm",
                                      "-o", "new/s.h5", "--dat", "new/s.dat"]),
        ("fixed h5 + dat, several scales", ["simulate", "coin", "--fixed", str(i["point"]),
                                            *SMALL, "-o", "f.h5", "--dat", "f.dat"]),
        ("fixed events + dat", ["simulate", "coin", "--fixed", str(i["dvs_point"]),
                                *SMALL, "-o", "e.h5", "--dat", "e.dat"]),
        ("dat export of RVSM spikes", ["dat", "export", str(i["dog4"]), "-o", "x.dat"]),
        ("dat export of events", ["dat", "export", str(i["events"]), "-o", "x.dat"]),
        ("dat import, wrong size", ["dat", "import", str(i["point"]), "--size", "3x5",
                                    "-o", "new/b.h5"]),
        ("events export of spikes", ["events", "export", str(i["fsm"]), "-o", "l.h5"]),
        ("events import of spikes", ["events", "import", str(i["fsm"]), "-o", "new/e.h5"]),
        ("events claims, bad --steps", ["events", "claims", "--steps", "1", "-o", "new"]),
        # events export: every format, refused after -o was checked
        ("events export AEDAT4 of four scales", ["events", "export", str(i["events"]),
                                                 "-o", "new/s.aedat4"]),
        ("events export, no such scale", ["events", "export", str(i["events"]),
                                          "--scale", "7", "-o", "l.h5"]),
        ("events export, another scene", ["events", "export", str(i["events"]), "--scene",
                                          str(i["reversed"]), "-o", "new/l.h5"]),
        ("events export CSV, no such scale", ["events", "export", str(i["events"]),
                                              "--scale", "2", "-o", "s.csv"]),
        # a refusal in the middle of writing: the partial file and its new folder go
        ("events import, a DSEC step that cannot hold two events",
         ["events", "import", str(i["dsec"]), "-o", "new/deep/e.h5"]),
        ("events import of one scale", ["events", "import", str(i["list_one"]),
                                        "-o", "e.npz"]),
        ("evaluate, another scene", ["evaluate", str(i["fsm"]), str(i["reversed"])]),
        ("robustness, bad --steps", ["robustness", "--steps", "0", "-o", "new"]),
        ("robustness, bad --ks", ["robustness", "--ks", "1,x", "-o", "new"]),
    ]


@pytest.mark.parametrize("index", range(21))
def test_a_refused_run_leaves_nothing(tmp_path, monkeypatch, inputs, capsys, index):
    name, argv = _cases(inputs)[index]
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    before = _listing(work)
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, (name, err)
    assert err.count("rvsm: error:") == 1 and "Traceback" not in err, name
    assert _listing(work) == before, (name, _listing(work))


def test_the_reported_repro_leaves_no_partial_h5(tmp_path, monkeypatch, capsys):
    """Issue 33's repro: ``simulate coin --size 31x45 --frames 3 --model fsm -o s.h5
    --dat s.dat`` left ``.s.XXXX.partial.h5`` every time."""
    monkeypatch.chdir(tmp_path)
    code = main(["simulate", "coin", "--size", "31x45", "--frames", "3", "--model", "fsm",
                 "-o", "s.h5", "--dat", "s.dat"])
    assert code == 2 and "divisible by 8" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_an_existing_output_survives_a_refused_rerun(tmp_path, monkeypatch, inputs, capsys):
    """A refused run never touches the outputs a previous run left."""
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "coin", "--size", "16x16", *SMALL, "--model", "fsm",
                 "-o", "s.h5", "--dat", "s.dat"]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert main(["simulate", "coin", "--size", "16x16", *SMALL, "--model", "dog4",
                 "-o", "s.h5", "--dat", "s.dat"]) == 2
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    with h5py.File(tmp_path / "s.h5") as f:
        assert np.asarray(f.attrs["shape"])[1] == 1  # still the FSM run's file


def test_blosc_without_hdf5plugin_is_an_environment_failure(tmp_path, monkeypatch, inputs,
                                                            capsys):
    """--compression blosc without hdf5plugin: exit 3 naming the package, nothing left."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(__import__("sys").modules, "hdf5plugin", None)  # not importable
    code = main(["events", "export", str(inputs["events"]), "--compression", "blosc",
                 "-o", "l.h5"])
    err = capsys.readouterr().err
    assert code == 3 and "pip install hdf5plugin" in err and "gzip" in err
    assert list(tmp_path.iterdir()) == []


def test_aedat4_without_faery_is_an_environment_failure(tmp_path, monkeypatch, inputs,
                                                        capsys):
    """An AEDAT4 export without faery: exit 3 naming the package, nothing left."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(__import__("sys").modules, "faery", None)  # not importable
    code = main(["events", "export", str(inputs["events"]), "--scale", "0",
                 "-o", "s.aedat4"])
    err = capsys.readouterr().err
    assert code == 3 and "pip install faery" in err
    assert list(tmp_path.iterdir()) == []
