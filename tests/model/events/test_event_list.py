"""HDF5 event lists (:mod:`rvsm.model.events.event_list`): the layout, round trips,
chunked reading, scoring from the list, atomic writes and damaged files."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from rvsm.model.events.config import EventConfig
from rvsm.model.events.event_list import (
    STEP_US,
    EventListWriter,
    is_event_list,
    open_event_list,
)
from rvsm.model.events.reconstruction import evaluate_events
from rvsm.model.events.twin import sample_events
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import load_scene
from rvsm.model.sensors.files import open_spikes
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.source import array_source


@pytest.fixture(scope="module")
def train():
    scene = load_scene("flyball", size=(20, 24), num_frames=6)
    return scene, sample_events(scene, EventConfig("dog2", contrast=0.1))


def _write(path: Path, train, chunk_steps: int = 7) -> None:
    _, t = train
    copy_source(array_source(t.events, t.meta),
                EventListWriter(path, t.references, t.config.contrasts), t.meta, chunk_steps)


def test_layout_and_round_trip(tmp_path: Path, train) -> None:
    scene, t = train
    path = tmp_path / "list.h5"
    _write(path, train)
    assert is_event_list(path)
    ev = t.events
    step, scale, y, x = np.nonzero(ev)  # C order: the list's order
    with h5py.File(path) as f:
        assert np.array_equal(f["events/t"][:], step * STEP_US)
        assert np.array_equal(f["events/x"][:], x) and np.array_equal(f["events/y"][:], y)
        assert np.array_equal(f["events/scale"][:], scale)
        assert np.array_equal(f["events/p"][:], (ev[step, scale, y, x] > 0).astype(np.uint8))
        idx = f["step_to_idx"][:]
        assert idx[0] == 0 and idx[-1] == len(step)
        assert np.array_equal(np.diff(idx), np.count_nonzero(ev, axis=(1, 2, 3)))
        ms = f["ms_to_idx"][:]
        stamps = f["events/t"][:]
        for m, i in enumerate(ms):
            assert np.all(stamps[:i] < m * 1000) and np.all(stamps[i:] >= m * 1000)
        assert np.array_equal(f["references"][:], t.references)
    with open_event_list(path) as src:
        assert src.shape == ev.shape
        for t0, t1 in ((0, 5), (5, 33), (33, ev.shape[0])):
            assert np.array_equal(src.read(t0, t1), ev[t0:t1])
        r = evaluate_events(src, scene)
    assert r == evaluate_events(array_source(ev, t.meta), scene)
    with open_spikes(path) as src:  # every reader takes an event list
        assert np.array_equal(src.read(0, ev.shape[0]), ev)


def test_failed_write_leaves_nothing_and_damage_is_refused(tmp_path: Path, train) -> None:
    _, t = train
    path = tmp_path / "list.h5"
    bad = EventListWriter(path, t.references[:1], t.config.contrasts)
    with pytest.raises(RvsmError, match="do not fit"):
        copy_source(array_source(t.events, t.meta), bad, t.meta)
    assert not path.exists() and not list(tmp_path.iterdir())
    _write(path, train)
    with h5py.File(path, "a") as f:
        f["step_to_idx"][3] = 10**9
    with pytest.raises(RvsmError, match="damaged"):
        open_event_list(path)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.attrs["format"] = "something"
    assert not is_event_list(other)
    with pytest.raises(RvsmError, match="not an rvsm event list"):
        open_event_list(other)
