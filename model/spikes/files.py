"""Spike files of the dense formats behind one entry point, chosen by suffix.

:func:`open_spike_file` opens ``.h5`` / ``.hdf5`` lazily (:mod:`.h5`) and ``.npz`` in
memory (:mod:`.npz`) as a :class:`~.source.SpikeSource`; :func:`write_spikes` writes a
whole array to either; :func:`copy_source` streams a source into a sink (:mod:`.sinks`).
Every file a sensor writes, HDF5 event lists included, is opened by
:func:`rvsm.model.sensors.files.open_spikes` (above this package and the event lists').
"""

from __future__ import annotations

import os

import numpy as np

from rvsm.model.spikes.arrays import check_spikes
from rvsm.model.spikes.h5 import H5SpikeWriter, is_h5_path, open_h5
from rvsm.model.spikes.npz import load_spikes, save_spikes
from rvsm.model.spikes.sinks import SpikeSink, fill_sink
from rvsm.model.spikes.source import SpikeSource, array_source


def open_spike_file(path: str | os.PathLike) -> SpikeSource:
    """Open an ``.h5`` (lazily) or ``.npz`` (in memory) spike file for reading."""
    if is_h5_path(path):
        return open_h5(path)
    spikes, meta = load_spikes(path)
    src = array_source(spikes, meta)
    src.path = str(path)
    return src


def write_spikes(path: str | os.PathLike, spikes: np.ndarray, meta: dict,
                 chunk_steps: int = 256) -> None:
    """Write a whole spike array to ``.h5`` (chunked) or ``.npz``, by suffix."""
    if not is_h5_path(path):
        save_spikes(path, spikes, meta)
        return
    arr = check_spikes(np.asarray(spikes), str(path))
    copy_source(array_source(arr, meta), H5SpikeWriter(path), meta, chunk_steps)


def copy_source(source: SpikeSource, sink: SpikeSink, meta: dict,
                chunk_steps: int = 256) -> None:
    """Stream every step of ``source`` into ``sink``."""
    fill_sink(sink, source.shape, meta, source.read, chunk_steps)
