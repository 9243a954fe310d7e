"""Other tools' event files come in (issue 42, deliverable 2): each file written by the
tool made for it (dv-processing's AEDAT4, faery's EVT 3, CSV, evlib's HDF5) is imported
by :mod:`rvsm.model.events.event_readers` with identical events ``(t, x, y, p)``; the
size comes from the header or is guessed and said; polarity conventions; a missing
column named; unsorted time stamps name the first event that goes back. The writers are
the ``community`` extra (skipped, naming the package, when missing)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from rvsm.model.events.event_readers import ImportOptions, open_event_file, reader_for
from rvsm.model.events.sensor_files import SensorFileWriter
from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.source import array_source
from tests.model.events.test_community_readers import community_reader

H, W = 20, 30


@pytest.fixture(scope="module")
def events():
    """``(t us, x, y, p 0/1)`` columns of random events, one a pixel and 25 us step, t a
    multiple of 25 (so a dense step keeps each exactly)."""
    rng = np.random.default_rng(42)
    dense = rng.choice([-1, 0, 1], p=[0.03, 0.94, 0.03], size=(80, H, W))
    step, y, x = np.nonzero(dense)
    return {"t": step.astype(np.int64) * 25, "x": x.astype(np.uint16),
            "y": y.astype(np.uint16), "p": (dense[step, y, x] > 0).astype(np.uint8)}


def _imported(path, **options) -> tuple[list[tuple[int, int, int, int]], dict]:
    """The events an import reads from ``path`` as sorted ``(t us, x, y, p 0/1)``."""
    _, source = open_event_file(path, ImportOptions(**options))
    with source:
        dense = source.read(0, source.num_steps)
        step, _, y, x = np.nonzero(dense)
        rows = zip((step * source.meta["step_us"]).tolist(), x.tolist(), y.tolist(),
                   (dense[step, 0, y, x] > 0).astype(int).tolist(), strict=True)
        return sorted(rows), dict(source.meta) | {"shape": source.shape}


def _rows(ev) -> list[tuple[int, int, int, int]]:
    return sorted(zip(ev["t"].tolist(), ev["x"].tolist(), ev["y"].tolist(),
                      ev["p"].astype(int).tolist(), strict=True))


def test_aedat4_written_by_dv_processing(tmp_path, events):
    dv = community_reader("dv_processing", "dv-processing")
    path = tmp_path / "dv.aedat4"
    writer = dv.io.MonoCameraWriter(str(path), dv.io.MonoCameraWriter.EventOnlyConfig(
        "DVXplorer_test", (W, H)))
    store = dv.EventStore()
    for t, x, y, p in zip(*(events[c].tolist() for c in "txyp"), strict=True):
        store.push_back(t, x, y, bool(p))
    writer.writeEvents(store)
    del writer  # closes the file
    assert reader_for(path).name == "AEDAT4"
    got, meta = _imported(path)
    assert got == _rows(events)
    assert meta["shape"][2:] == (H, W) and meta["size_from"] == "its AEDAT4 header"


@pytest.mark.parametrize("version", ["evt3", "evt2"])
def test_evt_written_by_faery(tmp_path, events, version):
    faery = community_reader("faery", "faery")
    path = tmp_path / "f.raw"
    packet = np.zeros(events["t"].size, dtype=faery.EVENTS_DTYPE)
    packet["t"], packet["x"], packet["y"] = events["t"], events["x"], events["y"]
    packet["on"] = events["p"] > 0
    with faery.evt.Encoder(str(path), version=version, zero_t0=False, dimensions=(W, H),
                           enforce_monotonic=True) as encoder:
        encoder.write({"events": packet})
    got, meta = _imported(path)
    assert got == _rows(events) and meta["shape"][2:] == (H, W)
    assert meta["size_from"] == "its EVT header"
    # the same events with a header that gives no size: the largest pixel + 1, said
    body = path.read_bytes().split(b"% geometry")[1].split(b"\n", 1)[1]
    bare = tmp_path / "bare.raw"
    bare.write_bytes(f"% evt {version[3]}.0\n".encode() + body)
    got, meta = _imported(bare)
    assert got == _rows(events) and meta["size_from"] == "guess"
    assert meta["shape"][2:] == (int(events["y"].max()) + 1, int(events["x"].max()) + 1)


@pytest.mark.parametrize("polarity", ["0/1", "-1/1", "bool"])
def test_csv_with_any_polarity_convention(tmp_path, events, polarity):
    community_reader("faery", "faery")
    p = {"0/1": events["p"].astype(int), "-1/1": np.where(events["p"] > 0, 1, -1),
         "bool": np.where(events["p"] > 0, "true", "false")}[polarity]
    lines = ["timestamp,x,y,polarity"] + [f"{t},{x},{y},{q}" for t, x, y, q in zip(
        events["t"].tolist(), events["x"].tolist(), events["y"].tolist(), p.tolist(),
        strict=True)]
    path = tmp_path / "e.csv"
    path.write_text("\n".join(lines) + "\n")
    got, meta = _imported(path, size=(H, W))
    assert got == _rows(events) and meta["size_from"] == "--size"


def test_evlib_hdf5_written_by_evlib(tmp_path, events):
    evlib = community_reader("evlib", "evlib")
    path = tmp_path / "evlib.h5"
    evlib.save_events_to_hdf5(events["x"].astype(np.int64), events["y"].astype(np.int64),
                              events["t"] / 1e6, np.where(events["p"] > 0, 1, -1), str(path))
    with h5py.File(path) as f:  # evlib's layout: seconds, -1/1
        assert f["events/ts"].dtype == np.float64 and f["events/ps"][...].min() == -1
    assert reader_for(path).name.startswith("evlib")
    got, meta = _imported(path)
    assert got == _rows(events) and meta["size_from"] == "guess"


def test_text_export_reads_in_evlib_and_faery_as_documented(tmp_path, events):
    evlib, faery = community_reader("evlib", "evlib"), community_reader("faery", "faery")
    dense = np.zeros((80, 1, H, W), np.int8)
    dense[events["t"] // 25, 0, events["y"], events["x"]] = np.where(events["p"] > 0, 1, -1)
    path = tmp_path / "e.txt"
    copy_source(array_source(dense, {"model": "fsm"}), SensorFileWriter(path), {}, 30)
    frame = evlib.load_events(str(path)).collect()  # no options
    got = sorted(zip(frame["t"].cast(int).to_list(), frame["x"].to_list(),
                     frame["y"].to_list(), (frame["polarity"] > 0).cast(int).to_list(),
                     strict=True))
    assert got == _rows(events)
    props = faery.CsvProperties(has_header=True, separator=b" ", t_index=0, x_index=1,
                                y_index=2, on_index=3, t_scale=1e6, on_value=b"1",
                                off_value=b"-1", skip_errors=False)  # as reading_hint says
    stream = faery.events_stream_from_file(path, file_type="csv", csv_properties=props,
                                           dimensions_fallback=(W, H))
    ev = np.concatenate(list(stream))
    assert sorted(zip(ev["t"].astype(int).tolist(), ev["x"].tolist(), ev["y"].tolist(),
                      ev["on"].astype(int).tolist(), strict=True)) == _rows(events)
    back, meta = _imported(path)  # and back in, the size from its header line
    assert back == _rows(events) and meta["shape"][2:] == (H, W)


def test_a_missing_column_is_named(tmp_path):
    community_reader("faery", "faery")
    csv = tmp_path / "e.csv"
    csv.write_text("t,x,y\n0,1,2\n25,2,3\n")
    with pytest.raises(RvsmError, match=r"no column 'p' \(polarity\) in .*e\.csv"):
        _imported(csv)
    dsec = tmp_path / "d.h5"
    with h5py.File(dsec, "w") as f:
        for c in "txy":
            f[f"events/{c}"] = np.arange(3)
    with pytest.raises(RvsmError, match=r"no column 'p' \(polarity\) in .*d\.h5 \(it has "
                       "events/t, events/x, events/y"):
        _imported(dsec)
    evl = tmp_path / "l.h5"
    with h5py.File(evl, "w") as f:
        for c in ("ts", "xs", "ps"):
            f[f"events/{c}"] = np.arange(3)
    with pytest.raises(RvsmError, match=r"no column 'y' \(row\)"):
        _imported(evl)


def test_unsorted_stamps_name_the_first_event_that_goes_back(tmp_path):
    path = tmp_path / "d.h5"
    with h5py.File(path, "w") as f:
        f["events/t"] = np.array([0, 25, 50, 75, 60, 100])
        f["events/x"] = f["events/y"] = np.arange(6)
        f["events/p"] = np.ones(6, np.uint8)
    with pytest.raises(RvsmError, match=r"go back at event 4 \(events/t 60 us after 75 us "
                       r"at event 3\)"):
        _imported(path)


def test_mixed_polarity_conventions_are_refused(tmp_path):
    path = tmp_path / "d.h5"
    with h5py.File(path, "w") as f:
        f["events/t"] = np.array([0, 25, 50])
        f["events/x"] = f["events/y"] = np.arange(3)
        f["events/p"] = np.array([1, 0, -1], np.int8)
    with pytest.raises(RvsmError, match="one convention a file"):
        _imported(path)
