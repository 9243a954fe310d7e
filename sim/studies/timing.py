"""Timings of the studies that measure runs, not numba's first compile."""

from __future__ import annotations

from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.loaders import load_scene

__all__ = ["compile_float_engine"]


def compile_float_engine(config: SamplerConfig) -> None:
    """Compile the float twin's kernels for ``config`` on a 16x24 scene of two frames, so
    a clock started after it measures the run (a no-op when numba's cache holds them)."""
    sample(load_scene("coin", size=(16, 24), num_frames=2), config)
