"""The spike camera as a registered :class:`~.capabilities.Sensor`: :data:`SPIKE_CAMERA`.

Its float twin is the sampler (:mod:`rvsm.model.sampling`), its decoder the
reconstructions of :mod:`rvsm.model.decode` (TFI/TFP for FSM, the RVSM adjoint, the
least-squares inverse), whole-array or streamed; its files are spike files (``.npz``,
HDF5, the camera's ``.dat``), of kind ``float``, ``fixed`` or ``camera``.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.decode.evaluation import evaluate_spikes
from rvsm.model.decode.reconstruction import METHODS
from rvsm.model.decode.streaming import evaluate_source
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import SPIKE
from rvsm.model.sampling.config import SamplerConfig, SpikeTrain
from rvsm.model.sampling.twin import sample, stream_float
from rvsm.model.scene.scene import Scene
from rvsm.model.sensors.capabilities import Sensor
from rvsm.model.sensors.scene_fit import check_scene_fits
from rvsm.model.spikes.sinks import SpikeSink
from rvsm.model.spikes.source import SpikeSource

__all__ = ["SPIKE_CAMERA", "evaluate_spike_file", "run_float_twin"]


def evaluate_spike_file(source: SpikeSource, scene: Scene, method: str = "auto",
                        match: str = "gain", stream: bool = False) -> dict:
    """Reconstruct the spikes of ``source`` with the model and thresholds its meta
    records and score them against ``scene`` (:func:`evaluate_spikes`, or chunk by chunk
    :func:`evaluate_source` when ``stream``)."""
    check_scene_fits(scene, source.shape)
    meta = source.meta
    model = meta.get("model")
    phis = meta.get("phis")
    if model is None or phis is None:
        raise RvsmError("the spike file's meta lacks 'model' or 'phis'; re-run rvsm "
                        "simulate")
    phis = np.asarray(phis, dtype=np.float64)
    if stream:
        return evaluate_source(source, scene, model, phis, method=method, match=match)
    return evaluate_spikes(source.read(0, source.num_steps), scene, model, phis,
                           method=method, match=match)


def run_float_twin(scene: Scene, config: SamplerConfig, sink: SpikeSink, *,
                   chunk_steps: int, engine: str, progress: bool) -> SpikeTrain:
    """The sampler's run pipeline (:func:`stream_float`), the spike camera's float twin."""
    return stream_float(scene, config, sink, chunk_steps=chunk_steps, engine=engine,
                        progress=progress)


def _float_of_point(scene: Scene, point: DesignPoint,
                    progress: bool) -> tuple[np.ndarray, dict]:
    """The float sampler ``point`` approximates, over the whole scene."""
    train = sample(scene, point.sampler_config(), progress=progress)
    return train.spikes, train.meta


#: The spike camera (SPEC sections 2-6).
SPIKE_CAMERA = Sensor(
    kind=SPIKE,
    file_kinds=("float", "fixed", "camera"),
    float_twin=run_float_twin,
    float_of_point=_float_of_point,
    evaluate=evaluate_spike_file,
    methods=METHODS,
    decoding="spikes are decoded by TFI/TFP, the RVSM adjoint or the least-squares inverse",
)
