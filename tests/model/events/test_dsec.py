"""Files in DSEC's layout read as dense events (:mod:`rvsm.model.events.dsec`) and through
``rvsm events import`` (issue 33, finding 1: the import refused them)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from rvsm.model.events.dsec import is_dsec_layout, open_dsec_events
from rvsm.model.events.event_list import EventListWriter
from rvsm.model.infra.errors import RvsmError
from rvsm.model.sensors.files import load_any_spikes
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.source import array_source
from rvsm.sim.cli import main


def write_dsec(path: Path, t, x, y, p, t_offset: int = 0, ms_to_idx: bool = True) -> Path:
    """A file as DSEC publishes them: uint32 time stamps relative to ``t_offset``, uint16
    pixels, uint8 polarities, ``ms_to_idx[m]`` the first event at or after ``m`` ms."""
    t = np.asarray(t, dtype=np.uint32)
    with h5py.File(path, "w") as f:
        f["events/t"], f["events/x"] = t, np.asarray(x, np.uint16)
        f["events/y"], f["events/p"] = np.asarray(y, np.uint16), np.asarray(p, np.uint8)
        if ms_to_idx:
            ms = np.arange(int(t[-1]) // 1000 + 2) * 1000
            f["ms_to_idx"] = np.searchsorted(t, ms, "left").astype(np.uint64)
        f["t_offset"] = np.int64(t_offset)
    return path


@pytest.fixture
def random_dsec(tmp_path):
    """Random events of a 6x10 sensor over 3.1 ms, at most one per pixel and 25 us step."""
    rng = np.random.default_rng(7)
    dense = rng.choice([-1, 0, 1], p=[0.05, 0.9, 0.05], size=(125, 1, 6, 10)).astype(np.int8)
    step, _, y, x = np.nonzero(dense)
    t = step * 25 + rng.integers(0, 25, step.size)  # anywhere inside the step
    order = np.argsort(t, kind="stable")
    path = write_dsec(tmp_path / "dsec.h5", t[order], x[order], y[order],
                      (dense[step, 0, y, x] > 0)[order], t_offset=1_700_000_000)
    return path, dense


@pytest.mark.parametrize("ms_to_idx", [True, False])
def test_dense_events_by_step(random_dsec, tmp_path, ms_to_idx):
    path, dense = random_dsec
    if not ms_to_idx:
        with h5py.File(path, "a") as f:
            del f["ms_to_idx"]
    assert is_dsec_layout(path)
    with open_dsec_events(path, size=(6, 10)) as src:
        assert src.shape == dense.shape
        for t0, t1 in ((0, 125), (0, 39), (39, 41), (40, 80), (117, 125)):
            assert np.array_equal(src.read(t0, t1), dense[t0:t1]), (t0, t1)
        assert src.meta["t_offset"] == 1_700_000_000 and src.meta["model"] == "fsm"


def test_size_from_the_largest_pixel_and_refusals(tmp_path):
    path = write_dsec(tmp_path / "a.h5", [0, 30, 40], [2, 7, 1], [0, 3, 4], [1, 0, 1])
    with open_dsec_events(path) as src:
        assert src.shape == (2, 1, 5, 8)
    with pytest.raises(RvsmError, match="outside 4x8; pass a larger --size"):
        open_dsec_events(path, size=(4, 8))
    same = write_dsec(tmp_path / "b.h5", [0, 30, 40], [2, 7, 7], [0, 3, 3], [1, 0, 1])
    with open_dsec_events(same) as src, pytest.raises(RvsmError, match="smaller --step-us"):
        src.read(0, 2)
    with open_dsec_events(same, step_us=10) as src:  # 10 us steps separate them
        assert src.shape[0] == 5 and src.read(0, 5)[3:5, 0, 3, 7].tolist() == [-1, 1]
    bad = write_dsec(tmp_path / "c.h5", [5, 3], [0, 0], [0, 0], [1, 1])
    with pytest.raises(RvsmError, match="go back at event 1"):
        open_dsec_events(bad)


def test_rvsm_events_import_reads_the_dsec_layout(random_dsec, tmp_path, capsys):
    path, dense = random_dsec
    out = tmp_path / "e.h5"
    assert main(["events", "import", str(path), "--size", "6x10", "-o", str(out)]) == 0
    said = f"{np.count_nonzero(dense):,} events of 1 scale, 125 steps of 6x10, from DSEC HDF5"
    assert said in capsys.readouterr().out
    events, meta = load_any_spikes(out)
    assert np.array_equal(events, dense) and meta["source_format"] == "dsec"
    # our own list is not DSEC's: --size is refused there
    copy_source(array_source(dense, {"model": "fsm"}),
                EventListWriter(tmp_path / "l.h5", np.zeros((1, 6, 10)), np.ones(1)),
                {"model": "fsm"})
    assert main(["events", "import", str(tmp_path / "l.h5"), "--size", "6x10",
                 "-o", str(tmp_path / "x.h5")]) == 2
    assert "is an rvsm event list, which says its own size" in capsys.readouterr().err
