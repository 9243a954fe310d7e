"""The event sensor (RVSM-DVS, SPEC section 7) as a registered
:class:`~.capabilities.Sensor`: :data:`EVENT_SENSOR`.

Its float twin is :mod:`rvsm.model.events`; its decoder the least-squares inverse of the
log responses (:func:`rvsm.model.events.reconstruction.evaluate_events`) with the
references the sensor captured: reported by an event list, the fixed-point twin's
integer ones for its files (:func:`fixed_references`, from the design point in the
meta), else the float model's regenerated from the scene. Its files are event files (the
spike-file formats, ``meta["kind"] = "events"``) and HDF5 event lists
(:mod:`rvsm.model.events.event_list`).
"""

from __future__ import annotations

import numpy as np

from rvsm.model.events.config import EventConfig, EventTrain
from rvsm.model.events.reconstruction import evaluate_events
from rvsm.model.events.twin import sample_events, stream_events
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.event_references import fixed_event_references
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import DVS
from rvsm.model.scene.scene import Scene
from rvsm.model.sensors.capabilities import Sensor
from rvsm.model.sensors.scene_fit import check_scene_fits
from rvsm.model.spikes.sinks import SpikeSink
from rvsm.model.spikes.source import SpikeSource

__all__ = ["EVENT_SENSOR", "evaluate_event_file", "fixed_references", "run_float_twin"]


def fixed_references(scene: Scene, meta: dict) -> tuple[np.ndarray, np.ndarray]:
    """``(references (S, H, W), contrasts (S,))`` in log units of the fixed-point twin
    whose design point ``meta`` records, on ``scene``."""
    try:
        point = DesignPoint(**meta["design_point"]).with_size(*scene.shape)
    except (TypeError, RvsmError) as exc:
        raise RvsmError(f"the event file's design point is not valid ({exc})") from None
    return fixed_event_references(scene, point)


def evaluate_event_file(source: SpikeSource, scene: Scene, method: str = "auto",
                        match: str = "gain", stream: bool = False) -> dict:
    """Decode and score the events of ``source`` (``method`` is the one the decoder has,
    ``"auto"``; the file is always read chunk by chunk)."""
    check_scene_fits(scene, source.shape, "events",
                     imported=bool(source.meta.get("contrast_assumed")))
    reported = fixed_references if source.meta.get("design_point") is not None else None
    return evaluate_events(source, scene, match=match, reported=reported)


def run_float_twin(scene: Scene, config: EventConfig, sink: SpikeSink, *,
                   chunk_steps: int, engine: str, progress: bool) -> EventTrain:
    """The event sensor's run pipeline (:func:`stream_events`), its float twin."""
    return stream_events(scene, config, sink, chunk_steps=chunk_steps, engine=engine,
                         progress=progress)


def _float_of_point(scene: Scene, point: DesignPoint,
                    progress: bool) -> tuple[np.ndarray, dict]:
    """The float event sensor ``point`` approximates, over the whole scene."""
    train = sample_events(scene, point.event_config())
    return train.events, train.meta


#: The event sensor, RVSM-DVS (SPEC section 7).
EVENT_SENSOR = Sensor(
    kind=DVS,
    file_kinds=("events",),
    float_twin=run_float_twin,
    float_of_point=_float_of_point,
    evaluate=evaluate_event_file,
    methods=("auto",),
    decoding="events are decoded by the least-squares inverse of their log responses",
)
