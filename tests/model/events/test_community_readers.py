"""Event exports read by the community's own tools (issue 33, finding 1): evlib loads the
HDF5 event list (no filter plugin), DSEC's slicing rule (re-derived from its description
of ``ms_to_idx``) finds every event, dv-processing and faery read AEDAT4, faery EVT 3
and CSV. The readers are the test-only extra ``community`` (``pip install -e
'.[community]'``); a test whose reader is missing is skipped, saying which."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import h5py
import numpy as np
import pytest

from rvsm.model.events.config import EventConfig
from rvsm.model.events.event_list import STEP_US, EventListWriter
from rvsm.model.events.sensor_files import SensorFileWriter
from rvsm.model.events.twin import sample_events
from rvsm.model.scene.loaders import load_scene
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.source import array_source


def community_reader(module: str, package: str):
    """Import a community reader, or skip naming the package (the ``community`` extra)."""
    if importlib.util.find_spec(module) is None:
        pytest.skip(f"{package} is not installed (pip install -e '.[community]')")
    return __import__(module)


@pytest.fixture(scope="module")
def dog4():
    """dog4 events with noise on a moving scene: scales share pixels and steps."""
    scene = load_scene("flyball", size=(24, 32), num_frames=7)  # 60 steps: 1.5 ms
    train = sample_events(scene, EventConfig("dog4", contrast=0.05), engine="numpy")
    assert np.count_nonzero(train.events) > 200
    return train


def _tuples(events: np.ndarray, scale: int | None = None) -> list[tuple[int, int, int, int]]:
    """Sorted ``(t us, x, y, polarity +-1)`` of every scale's events (or one scale's)."""
    ev = events if scale is None else events[:, scale:scale + 1]
    step, _, y, x = np.nonzero(ev)
    return sorted(zip((step * STEP_US).tolist(), x.tolist(), y.tolist(),
                      ev[step, _, y, x].astype(int).tolist(), strict=True))


def _export(path: Path, train, **kw) -> Path:
    copy_source(array_source(train.events, train.meta),
                EventListWriter(path, train.references, train.config.contrasts, **kw),
                train.meta, 7)
    return path


def test_the_list_needs_no_filter_plugin_and_says_what_scale_means(tmp_path, dog4):
    path = _export(tmp_path / "list.h5", dog4)
    with h5py.File(path) as f:
        for name in ("t", "x", "y", "p", "scale"):
            assert f[f"events/{name}"].compression == "gzip"  # HDF5's built-in deflate
        semantics = f.attrs["scale_semantics"].decode()
        assert "merges 4 sensors into one" in semantics and "--scale" in semantics
        assert f["events/scale"].attrs["description"].decode() == semantics
        assert f.attrs["model"].decode() == "dog4" and f.attrs["compression"] == b"gzip"
    shared = {(t, x, y) for t, x, y, _ in _tuples(dog4.events, 0)} & \
        {(t, x, y) for t, x, y, _ in _tuples(dog4.events, 1)}
    assert shared  # what the attribute warns about happens here


def test_evlib_loads_the_list_and_one_scale(tmp_path, dog4):
    evlib = community_reader("evlib", "evlib")
    for kw, scale in (({}, None), ({"scale": 2}, 2)):
        path = _export(tmp_path / f"list{scale}.h5", dog4, **kw)
        frame = evlib.load_events(str(path)).collect()
        t = frame["t"].cast(int).to_numpy()  # a Duration in microseconds
        got = sorted(zip(t.tolist(), frame["x"].to_list(), frame["y"].to_list(),
                         frame["polarity"].to_list(), strict=True))
        assert got == _tuples(dog4.events, scale)


def dsec_slice(path: Path, t_start_us: int, t_end_us: int) -> np.ndarray:
    """The events with ``t_start_us <= t_offset + t < t_end_us`` as ``(n, 4)`` rows of
    ``t, x, y, p``, by DSEC's published rule: ``t`` is relative to ``t_offset``;
    ``ms_to_idx[m]`` is the index of the first event whose time stamp is at or after
    ``m`` milliseconds, so the events of a window lie between ``ms_to_idx[floor(start /
    1 ms)]`` and ``ms_to_idx[ceil(end / 1 ms)]``, and are then cut by their own times."""
    with h5py.File(path) as f:
        offset = int(f["t_offset"][()])
        start, end = t_start_us - offset, t_end_us - offset
        index = f["ms_to_idx"][...]
        lo, hi = int(index[start // 1000]), int(index[-(-end // 1000)])
        t = f["events/t"][lo:hi]
        keep = (t >= start) & (t < end)
        cols = [f[f"events/{c}"][lo:hi][keep].astype(np.int64) for c in ("x", "y", "p")]
    return np.stack([t[keep].astype(np.int64) + offset, *cols], axis=1)


def test_dsec_slicing_finds_every_event_of_any_window(tmp_path, dog4):
    path = _export(tmp_path / "list.h5", dog4, scale=1)
    want = np.array(_tuples(dog4.events, 1))
    want[:, 3] = want[:, 3] > 0
    end = dog4.events.shape[0] * STEP_US
    for a, b in ((0, end), (0, 1000), (975, 1025), (1000, 2000), (end - 300, end),
                 (end - 25, end)):
        got = dsec_slice(path, a, b)
        sel = want[(want[:, 0] >= a) & (want[:, 0] < b)]
        assert sorted(map(tuple, got.tolist())) == sorted(map(tuple, sel.tolist())), (a, b)


@pytest.mark.parametrize("suffix", [".aedat4", ".raw", ".csv"])
def test_faery_reads_one_scale(tmp_path, dog4, suffix):
    faery = community_reader("faery", "faery")
    path = tmp_path / f"s{suffix}"
    copy_source(array_source(dog4.events, dog4.meta), SensorFileWriter(path, 3),
                dog4.meta, 6)
    if suffix == ".csv":  # faery's CSV reader takes the size from its caller
        assert path.read_text().splitlines()[0] == "t,x@32,y@24,on"
        stream = faery.events_stream_from_file(path, dimensions_fallback=(32, 24))
    else:
        stream = faery.events_stream_from_file(path)
    assert tuple(stream.dimensions()) == (32, 24)  # width, height
    events = np.concatenate(list(stream))
    got = sorted(zip(events["t"].astype(int).tolist(), events["x"].tolist(),
                     events["y"].tolist(), np.where(events["on"], 1, -1).tolist(),
                     strict=True))
    assert got == _tuples(dog4.events, 3)


def test_dv_processing_reads_the_aedat4_export(tmp_path, dog4):
    dv = community_reader("dv_processing", "dv-processing")
    path = tmp_path / "s.aedat4"
    copy_source(array_source(dog4.events, dog4.meta), SensorFileWriter(path, 0),
                dog4.meta, 6)
    recording = dv.io.MonoCameraRecording(str(path))
    assert tuple(recording.getEventResolution()) == (32, 24)
    assert recording.getCameraName() == "rvsm dog4 scale 0 of 4"
    rows = []
    while recording.isRunning():
        batch = recording.getNextEventBatch()
        if batch is not None:
            rows.extend(batch.numpy().tolist())
    got = sorted((int(t), int(x), int(y), 1 if p else -1) for t, x, y, p in rows)
    assert got == _tuples(dog4.events, 0)
