"""Every file a sensor writes behind one reader: spike files and HDF5 event lists.

:func:`open_spikes` opens an HDF5 event list (:mod:`rvsm.model.events.event_list`) as
dense events and any other ``.h5`` / ``.npz`` file as the spike file it is
(:func:`rvsm.model.spikes.files.open_spike_file`); :func:`load_any_spikes` reads a whole
small file. It sits above both formats' packages, so neither imports the other.
"""

from __future__ import annotations

import os

import numpy as np

from rvsm.model.events.event_list import is_event_list, open_event_list
from rvsm.model.spikes.arrays import check_spikes
from rvsm.model.spikes.files import open_spike_file
from rvsm.model.spikes.h5 import is_h5_path
from rvsm.model.spikes.source import SpikeSource

__all__ = ["load_any_spikes", "open_spikes"]


def open_spikes(path: str | os.PathLike) -> SpikeSource:
    """Open an ``.h5`` (lazily) or ``.npz`` (in memory) spike file for reading; an HDF5
    event list is read as dense events."""
    if is_h5_path(path) and is_event_list(path):
        return open_event_list(path)
    return open_spike_file(path)


def load_any_spikes(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Whole spike array and meta of an ``.h5`` or ``.npz`` file (small files only)."""
    with open_spikes(path) as src:
        return check_spikes(src.read(0, src.num_steps), str(path)), src.meta
