"""Every file a sensor writes behind one reader: spike files and HDF5 event lists.

:func:`open_spikes` opens an HDF5 event list (:mod:`rvsm.model.events.event_list`) as
dense events and any other ``.h5`` / ``.npz`` file as the spike file it is
(:func:`rvsm.model.spikes.files.open_spike_file`); :func:`load_any_spikes` reads a whole
small file. It sits above both formats' packages, so neither imports the other.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rvsm.model.events.event_list import is_event_list, open_event_list
from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.arrays import check_spikes
from rvsm.model.spikes.files import open_spike_file
from rvsm.model.spikes.h5 import is_h5_path
from rvsm.model.spikes.source import SpikeSource

__all__ = ["load_any_spikes", "open_spikes"]


def open_spikes(path: str | os.PathLike) -> SpikeSource:
    """Open an ``.h5`` (lazily) or ``.npz`` (in memory) spike file for reading; an HDF5
    event list is read as dense events. A file another tool wrote (the camera's ``.dat``,
    AEDAT4, EVT, CSV, DSEC's or evlib's HDF5) is refused, naming the command that
    converts it."""
    if is_h5_path(path) and is_event_list(path):
        return open_event_list(path)
    _refuse_foreign(Path(path))
    return open_spike_file(path)


def _refuse_foreign(p: Path) -> None:
    """Refuse a file that needs converting first, saying how."""
    from rvsm.model.events.community_files import is_evlib_layout
    from rvsm.model.events.dsec import is_dsec_layout
    from rvsm.model.events.event_readers import EVENT_READERS

    if not p.is_file():
        return  # the reader says it does not exist
    suffix = p.suffix.lower()
    if suffix == ".dat":
        raise RvsmError(f"{p} is a spike camera .dat (no header, no meta): convert it "
                        f"with rvsm dat import {p} --size HxW -o spikes.h5, then use "
                        "spikes.h5 (rvsm evaluate spikes.h5 SCENE)")
    foreign = (is_dsec_layout(p) or is_evlib_layout(p) if is_h5_path(p) else
               any(suffix in r.suffixes for r in EVENT_READERS))
    if foreign:
        raise RvsmError(f"{p} is another tool's event file: convert it with rvsm events "
                        f"import {p} -o events.h5, then use events.h5 (rvsm evaluate "
                        "events.h5 SCENE)")


def load_any_spikes(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Whole spike array and meta of an ``.h5`` or ``.npz`` file (small files only)."""
    with open_spikes(path) as src:
        return check_spikes(src.read(0, src.num_steps), str(path)), src.meta
