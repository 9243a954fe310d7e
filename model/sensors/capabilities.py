"""A sensor as a value: :class:`Sensor`, what the commands and studies ask of a sensor.

Nothing outside the registry (:mod:`.registry`) tells the spike camera from the event
sensor by name: a command looks the sensor up (:func:`~.registry.get_sensor`, or
:func:`~.registry.sensor_of_meta` for a file) and calls its capabilities. The lower
packages take the declarative :class:`~rvsm.model.kinds.sensor_kind.SensorKind` instead
(:attr:`Sensor.kind`); the fixed twin's rules per kind are
:mod:`rvsm.model.fixed.sensor_rules`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.kinds.sensor_kind import SensorKind
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.sinks import SpikeSink
from rvsm.model.spikes.source import SpikeSource

__all__ = ["Evaluate", "FloatTwin", "Sensor"]


class FloatTwin(Protocol):
    """A float twin's run pipeline: ``scene`` through ``config`` chunk by chunk into
    ``sink`` (:func:`rvsm.model.sampling.twin.stream_float`,
    :func:`rvsm.model.events.twin.stream_events`); returns the run's result."""

    def __call__(self, scene: Scene, config: Any, sink: SpikeSink, *, chunk_steps: int,
                 engine: str, progress: bool) -> Any: ...


class Evaluate(Protocol):
    """A decoder and its scores: reconstruct ``source`` and score it against ``scene``
    (``{"mse", "psnr", "ssim", "num_scored", "warmup", "method"}``); ``method`` and
    ``match`` as ``rvsm evaluate`` takes them, ``stream`` reads the source a chunk at a
    time (an HDF5 file)."""

    def __call__(self, source: SpikeSource, scene: Scene, method: str = "auto",
                 match: str = "gain", stream: bool = False) -> dict: ...


@dataclass(frozen=True)
class Sensor:
    """One registered sensor.

    - ``kind``: its declarative facts (name, output rule, the words of its reports);
    - ``file_kinds``: the ``meta["kind"]`` of the files it writes (float and fixed runs);
    - ``float_twin``: its float model's run pipeline (:class:`FloatTwin`);
    - ``float_of_point``: the float model a design point approximates, run over a whole
      scene: ``(scene, point, progress) -> (outputs (T, S, H, W) int8, meta)``;
    - ``evaluate``: its decoder and scores (:class:`Evaluate`), for its files of either
      twin;
    - ``methods``: the reconstruction methods its decoder takes (``"auto"`` first) and
      ``decoding``: how it decodes, in a few words (said when another is asked for).
    """

    kind: SensorKind
    file_kinds: tuple[str, ...]
    float_twin: FloatTwin
    float_of_point: Callable[[Scene, DesignPoint, bool], tuple[np.ndarray, dict]]
    evaluate: Evaluate
    methods: tuple[str, ...]
    decoding: str

    @property
    def name(self) -> str:
        """Its registry key, the name of its kind (``--sensor``, ``array.sensor``)."""
        return self.kind.name
