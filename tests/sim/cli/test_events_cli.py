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
