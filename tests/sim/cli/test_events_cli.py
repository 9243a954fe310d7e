"""``rvsm simulate --sensor dvs``: event files through the same writers, the same
events from both engines and file formats, options of the other sensor refused."""

import json

import numpy as np

from rvsm.model.sensors.files import load_any_spikes
from rvsm.sim.cli import main

SMALL = ["--size", "24x32", "--frames", "4", "--steps-per-frame", "8"]


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_simulate_dvs_writes_events(tmp_path, capsys):
    h5, npz = tmp_path / "e.h5", tmp_path / "e.npz"
    code, out, err = _run(capsys, "simulate", "flyball", *SMALL, "--sensor", "dvs",
                          "--model", "dog2", "--scale-contrast", "0.1,0.15", "--noise",
                          "-o", h5)
    assert code == 0, err
    assert "events" in out and "OFF" in out
    code, _, err = _run(capsys, "simulate", "flyball", *SMALL, "--sensor", "dvs",
                        "--model", "dog2", "--scale-contrast", "0.1,0.15", "--noise",
                        "--engine", "numpy", "--chunk-steps", "5", "-o", npz)
    assert code == 0, err
    a, meta = load_any_spikes(h5)
    b, _ = load_any_spikes(npz)
    assert np.array_equal(a, b) and np.count_nonzero(a) > 0
    assert meta["kind"] == "events" and meta["sensor"] == "dvs"
    assert meta["contrasts"] == [0.1, 0.15]
    code, out, err = _run(capsys, "evaluate", h5, "--json")
    assert code == 0, err
    result = json.loads(out)
    assert 20 < result["psnr"] < 80 and result["method"] == "events-inverse"
    assert _run(capsys, "evaluate", h5, "--method", "tfi")[0] == 2


def test_options_of_the_other_sensor_are_refused(tmp_path, capsys):
    out = tmp_path / "e.h5"
    for extra in (["--sensor", "dvs", "--phi", "3"], ["--sensor", "dvs", "--reset", "zero"],
                  ["--contrast", "0.3"], ["--sensor", "dvs", "--scale-contrast", "x"],
                  ["--sensor", "dvs", "--contrast", "-1"]):
        code, _, err = _run(capsys, "simulate", "flyball", *SMALL, *extra, "-o", out)
        assert code == 2, extra
        assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_events_export_import(tmp_path, capsys):
    ev, lst, back = tmp_path / "e.npz", tmp_path / "l.h5", tmp_path / "b.h5"
    assert _run(capsys, "simulate", "coin", *SMALL, "--sensor", "dvs", "--model", "gauss2",
                "--contrast", "0.05", "-o", ev)[0] == 0
    code, out, err = _run(capsys, "events", "export", ev, "-o", lst)
    assert code == 0 and "event list" in out, err
    assert _run(capsys, "events", "import", lst, "-o", back)[0] == 0
    a, _ = load_any_spikes(ev)
    b, meta = load_any_spikes(back)
    assert np.array_equal(a, b) and meta["kind"] == "events"
    one = json.loads(_run(capsys, "evaluate", ev, "--json")[1])
    two = json.loads(_run(capsys, "evaluate", lst, "--json")[1])
    assert one["psnr"] == two["psnr"]
    spikes = tmp_path / "s.npz"
    assert _run(capsys, "simulate", "coin", *SMALL, "-o", spikes)[0] == 0
    code, _, err = _run(capsys, "events", "export", spikes, "-o", tmp_path / "x.h5")
    assert code == 2 and "holds spikes" in err
    assert _run(capsys, "events", "export", ev, "-o", tmp_path / "x.npz")[0] == 2


def test_refusals_say_true_things_in_good_english(tmp_path, capsys):
    """Issue 33's words: grammar, articles, and the true reason for --dat and --fixed."""
    out = tmp_path / "e.h5"
    for extra, words in (
            (["--contrast", "0.3"], "--contrast applies only to --sensor dvs"),
            (["--contrast", "0.3", "--scale-contrast", "1"],
             "--contrast and --scale-contrast apply only to --sensor dvs"),
            (["--sensor", "dvs", "--phi", "3"], "--phi is the spike camera's"),
            (["--sensor", "dvs", "--dat", str(tmp_path / "e.dat")],
             "events have two polarities (ON/OFF); write events with rvsm events export"),
            (["--sensor", "dvs", "--fixed", str(tmp_path / "p.toml")],
             "--fixed takes the sensor from the design point")):
        code, _, err = _run(capsys, "simulate", "flyball", *SMALL, *extra, "-o", out)
        assert code == 2 and words in err, (extra, err)
        assert "not built yet" not in err
    assert not list(tmp_path.iterdir())


def test_an_existing_list_is_replaced_and_another_h5_named_with_its_article(tmp_path,
                                                                           capsys):
    events, lst = tmp_path / "e.h5", tmp_path / "list.h5"
    assert _run(capsys, "simulate", "flyball", *SMALL, "--sensor", "dvs", "--model", "fsm",
                "--engine", "numpy", "-o", events)[0] == 0
    for _ in range(2):  # re-running the export replaces its own list without --force
        code, out, err = _run(capsys, "events", "export", events, "-o", lst)
        assert code == 0, err
    import h5py

    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.zeros(3)
    code, _, err = _run(capsys, "events", "export", events, "-o", tmp_path / "other.h5")
    assert code == 2 and "holds an HDF5 file, not an event list" in err


def _dense_events(path, model: str, scales: int, steps: int = 24):
    """An event file of ``model`` (``scales`` scales, 24x32) with random events."""
    from rvsm.model.spikes.files import write_spikes

    rng = np.random.default_rng(3)
    dense = rng.choice([-1, 0, 1], p=[0.02, 0.96, 0.02],
                       size=(steps, scales, 24, 32)).astype(np.int8)
    write_spikes(path, dense, {"kind": "events", "sensor": "dvs", "model": model})
    return dense


def _dsec(path, t, x, y, p):
    import h5py

    with h5py.File(path, "w") as f:
        f["events/t"], f["events/x"] = np.asarray(t), np.asarray(x, np.uint16)
        f["events/y"], f["events/p"] = np.asarray(y, np.uint16), np.asarray(p, np.uint8)
    return path


def test_evaluate_of_a_foreign_file_names_the_command_that_converts_it(tmp_path, capsys):
    dat = tmp_path / "fsm.dat"
    dat.write_bytes(bytes(24 * 24 * 32 // 8))
    code, _, err = _run(capsys, "evaluate", dat, "flyball")
    assert code == 2 and err.count("\n") == 1
    assert f"rvsm dat import {dat} --size HxW -o spikes.h5" in err
    assert "zip directory" not in err
    dsec = _dsec(tmp_path / "d.h5", [25, 50], [1, 2], [1, 2], [1, 0])
    code, _, err = _run(capsys, "evaluate", dsec, "flyball")
    assert code == 2 and f"rvsm events import {dsec} -o events.h5" in err


def test_imported_events_of_another_step_count_name_the_matching_options(tmp_path, capsys):
    rng = np.random.default_rng(5)
    t = np.sort(rng.choice(np.arange(1, 24), 40)) * 25
    t[-1] = 23 * 25  # 24 steps: 4 frames of 8 steps
    dsec = _dsec(tmp_path / "d.h5", t, rng.integers(0, 32, 40), rng.integers(0, 24, 40),
                 rng.integers(0, 2, 40))
    imported = tmp_path / "e.h5"
    code, out, err = _run(capsys, "events", "import", dsec, "-o", imported, "--size",
                          "24x32", "--step-us", 25)
    assert code == 0, err
    code, _, err = _run(capsys, "evaluate", imported, "flyball", "--steps-per-frame", 8)
    assert code == 2 and err.count("\n") == 1
    assert "pass --frames 4 " in err and "= 24 steps" in err, err
    assert "or import it again with --steps 320" in err  # 41 frames of 8 steps
    code, _, err = _run(capsys, "evaluate", imported, "flyball", "--frames", 4)
    assert code == 2 and "pass --steps-per-frame 8" in err, err
    code, _, err = _run(capsys, "evaluate", imported, "flyball", "--frames", 4,
                        "--steps-per-frame", 8)
    assert code == 0, err
    longer = tmp_path / "long.h5"  # the recording ran on: --steps sets T
    code, out, err = _run(capsys, "events", "import", dsec, "-o", longer, "--size", "24x32",
                          "--steps", 40)
    assert code == 0 and "40 steps of 24x32" in out, err
    code, _, err = _run(capsys, "events", "import", dsec, "-o", tmp_path / "x.h5",
                        "--steps", 10)
    assert code == 2 and "pass --steps 24 or more" in err and not (tmp_path / "x.h5").exists()


def test_export_and_import_say_the_events_and_scales_written(tmp_path, capsys):
    events = tmp_path / "e.h5"
    dense = _dense_events(events, "dog4", 4)
    aedat = tmp_path / "s.aedat4"
    code, out, err = _run(capsys, "events", "export", events, "--scale", 2, "-o", aedat)
    assert code == 0, err
    n = int(np.count_nonzero(dense[:, 2]))
    assert f"{n:,} events of scale 2 alone (one of dog4's 4 scales), 24 steps of 24x32, " \
           "as AEDAT4" in out
    assert "4 scale(s)" not in out and "to read it: faery and evlib" in out
    code, out, err = _run(capsys, "events", "import", aedat, "-o", tmp_path / "b.h5")
    assert code == 0, err
    assert f"{n:,} events of 1 scale, " in out and "from AEDAT4 (read by faery" in out
    text = tmp_path / "s.txt"  # evlib's text: the options faery needs are said
    code, out, _ = _run(capsys, "events", "export", events, "--scale", 0, "-o", text)
    assert code == 0 and "evlib reads it as it is" in out and "separator=b' '" in out
    one = tmp_path / "one.h5"
    dense1 = _dense_events(one, "fsm", 1)
    code, out, _ = _run(capsys, "events", "export", one, "-o", tmp_path / "one.csv")
    assert code == 0
    assert f"{np.count_nonzero(dense1):,} events of fsm's one scale" in out
    assert "dimensions_fallback=(32, 24)" in out


def test_a_file_without_a_size_says_the_size_it_took(tmp_path, capsys):
    dsec = _dsec(tmp_path / "d.h5", [0, 30, 40], [2, 7, 1], [0, 3, 4], [1, 0, 1])
    code, out, err = _run(capsys, "events", "import", dsec, "-o", tmp_path / "e.h5")
    assert code == 0, err
    assert "warning" in err and "took 5x8, the largest y and x + 1" in err
    assert "3 events of 1 scale" in out and "size guessed" in out


def test_bad_foreign_input_exits_2_in_one_line_and_leaves_no_file(tmp_path, capsys):
    bad = tmp_path / "in"
    bad.mkdir()
    (bad / "nop.csv").write_text("t,x,y\n0,1,2\n")
    _dsec(bad / "back.h5", [0, 25, 50, 75, 60], [0, 1, 2, 3, 4], [0] * 5, [1] * 5)
    (bad / "odd.xyz").write_text("0 1 2 1\n")
    (bad / "head.csv").write_text("t,x,y,p\n")
    (bad / "noise.raw").write_bytes(np.random.default_rng(1).bytes(3000))
    (bad / "noise.aedat4").write_bytes(np.random.default_rng(2).bytes(3000))
    (bad / "pol.txt").write_text("0 1 2 5\n")
    for name, words in (("nop.csv", "no column 'p' (polarity)"),
                        ("back.h5", "go back at event 4"),
                        ("head.csv", "holds no events"),
                        ("noise.raw", "not an EVT file: it has no header"),
                        ("noise.aedat4", "not a readable AEDAT4 file (faery: bad magic"),
                        ("pol.txt", "not a readable CSV or text file"),
                        ("odd.xyz", "not an event file rvsm events import reads")):
        out = tmp_path / "out" / "e.h5"
        code, _, err = _run(capsys, "events", "import", bad / name, "-o", out)
        assert code == 2 and err.count("\n") == 1 and words in err, (name, err)
        assert "Traceback" not in err
        assert not (tmp_path / "out").exists()
