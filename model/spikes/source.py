"""Read access to spikes, whatever holds them: :class:`SpikeSource`.

A source has ``shape (T, S, H, W)``, ``meta`` and ``read(t0, t1)``, so readers stream any
spike file step range by step range. :func:`array_source` wraps an in-memory array;
:func:`rvsm.model.sensors.files.open_spikes` opens a file of any format,
:func:`rvsm.model.spikes.dat.dat_source` a camera ``.dat`` file.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np


class SpikeSource:
    """Read access to a spike file: ``shape (T, S, H, W)``, ``meta``, ``read(t0, t1)``.

    Use as a context manager (closes an HDF5 file).
    """

    def __init__(self, shape: tuple[int, ...], meta: dict,
                 reader: Callable[[int, int], np.ndarray],
                 closer: Callable[[], None] | None = None, path: str = ""):
        self.shape = tuple(int(v) for v in shape)
        self.meta = meta
        self._reader = reader
        self._closer = closer
        self.path = path

    @property
    def num_steps(self) -> int:
        """T."""
        return self.shape[0]

    def read(self, t0: int, t1: int) -> np.ndarray:
        """Spikes of steps ``t0 .. t1 - 1``: ``(t1 - t0, S, H, W) int8``."""
        return np.asarray(self._reader(int(t0), int(t1)), dtype=np.int8)

    def chunks(self, chunk_steps: int) -> Iterator[tuple[int, np.ndarray]]:
        """Yield ``(t0, spikes)`` over the whole file in chunks of ``chunk_steps``."""
        for t0 in range(0, self.num_steps, chunk_steps):
            t1 = min(t0 + chunk_steps, self.num_steps)
            yield t0, self.read(t0, t1)

    def close(self) -> None:
        if self._closer is not None:
            self._closer()
            self._closer = None

    def __enter__(self) -> SpikeSource:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def array_source(spikes: np.ndarray, meta: dict | None = None) -> SpikeSource:
    """An in-memory ``(T, S, H, W)`` array as a :class:`SpikeSource`."""
    arr = np.asarray(spikes)
    if arr.ndim == 3:
        arr = arr[:, None]
    return SpikeSource(arr.shape, meta or {}, lambda t0, t1: arr[t0:t1])
