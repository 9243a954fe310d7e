"""The float reference samplers: FSM and RVSM-DoG / RVSM-Gauss (SPEC section 2).

Every model integrates per step, then compares, then resets; the spike of step ``t`` is
decided from the accumulation that includes step ``t``. FSM is the one-scale case with a
1x1 kernel of weight 1 that only fires +1.

Two engines give bit-identical spikes: ``"fused"`` (default; numba kernels with the time
loop inside, :mod:`.fused`, run chunk by chunk by :mod:`.sampling_stream`) and ``"numpy"``
(the vectorised reference below). In both, receptive-field sums are linear, so the frames
are filtered once and the per-step drive is interpolated between filtered frames (SPEC
section 1's formula applied after the filter); only the dark current, new every step, is
filtered per step. Filtering uses the fixed float order of :mod:`.orbits`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.memory import require_spike_memory
from rvsm.model.infra.progress import progress_bar
from rvsm.model.kernels.orbits import orbit_receptive_sums
from rvsm.model.kernels.receptive_fields import ModelSpec, model_spec
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.scene.scene import Scene

RESET_MODES = ("zero", "subtract")
ENGINES = ("fused", "numpy")
DEFAULT_PHI = 400.0
DEFAULT_BLOCK_STEPS = 32


@dataclass(frozen=True)
class SamplerConfig:
    """Everything that decides a float sampler's spikes besides the scene.

    ``phi`` is the nominal threshold in 8-bit brightness units; ``scale_phi`` optionally
    overrides it per scale (length S); ``reset`` is ``"zero"`` (the paper) or
    ``"subtract"``; ``noise`` is ``None`` for a noiseless sensor.
    """

    model: str = "dog4"
    phi: float = DEFAULT_PHI
    scale_phi: tuple[float, ...] | None = None
    reset: str = "zero"
    noise: NoiseParams | None = None

    def __post_init__(self) -> None:
        spec = model_spec(self.model)
        object.__setattr__(self, "model", spec.name)
        if isinstance(self.phi, bool) or not np.isfinite(self.phi) or self.phi <= 0:
            raise RvsmError(f"threshold phi must be a finite number > 0, got {self.phi!r}")
        if self.scale_phi is not None:
            values = tuple(float(v) for v in self.scale_phi)
            if len(values) != spec.num_scales:
                raise RvsmError(
                    f"{spec.name} has {spec.num_scales} scale(s) but "
                    f"{len(values)} per-scale thresholds were given"
                )
            if not all(np.isfinite(v) and v > 0 for v in values):
                raise RvsmError(f"per-scale thresholds must be finite and > 0, got {values}")
            object.__setattr__(self, "scale_phi", values)
        if self.reset not in RESET_MODES:
            raise RvsmError(f"reset must be one of {RESET_MODES}, got {self.reset!r}")

    @property
    def spec(self) -> ModelSpec:
        """The parsed model (family, scales, kernels)."""
        return model_spec(self.model)

    @property
    def phis(self) -> np.ndarray:
        """Nominal threshold per scale, ``(S,) float64``."""
        if self.scale_phi is not None:
            return np.array(self.scale_phi, dtype=np.float64)
        return np.full(self.spec.num_scales, float(self.phi))

    def to_dict(self) -> dict:
        """Plain-JSON form, for spike-file metadata."""
        return {
            "model": self.model,
            "phi": float(self.phi),
            "scale_phi": list(self.scale_phi) if self.scale_phi is not None else None,
            "reset": self.reset,
            "noise": self.noise.to_dict() if self.noise is not None else None,
        }


@dataclass
class SpikeTrain:
    """Sampler output: ``spikes (T, S, H, W) int8`` in {-1, 0, 1} and its thresholds.

    ``thresholds`` is ``(S, H, W) float64``, the per-accumulator thresholds actually used
    (fixed-pattern noise included).
    """

    spikes: np.ndarray
    thresholds: np.ndarray
    config: SamplerConfig
    meta: dict = field(default_factory=dict)


def accumulator_thresholds(config: SamplerConfig, shape: tuple[int, int]) -> np.ndarray:
    """Per-accumulator thresholds ``(S, H, W) float64``: nominal, or with fixed pattern.

    Thresholds are clipped at 0; at a zero threshold the +1 comparison wins.
    """
    phis = config.phis
    if config.noise is None:
        thr = np.broadcast_to(phis[:, None, None], (len(phis),) + tuple(shape)).copy()
    else:
        thr = NoiseSource(config.noise, shape, len(phis)).thresholds(phis)
    return np.maximum(thr, 0.0)


def iter_step_drives(
    scene: Scene, config: SamplerConfig, block_steps: int = DEFAULT_BLOCK_STEPS
) -> Iterator[tuple[int, np.ndarray]]:
    """Yield ``(t, drive)`` for every step: ``drive (S, H, W) float64`` is the input of
    every accumulator at step ``t`` (receptive-field sum of brightness plus filtered dark
    current). The array is a reused buffer: consume it before the next iteration.

    Frames are filtered once; a step between frames is ``(1 - a) KF[f] + a KF[f+1]``
    (SPEC section 1's interpolation applied after the linear filter). Dark current is
    drawn and filtered in blocks of ``block_steps``. This is the numpy reference engine.
    """
    kernels = config.spec.kernels()
    filtered = orbit_receptive_sums(scene.frames, kernels)  # (F, S, H, W)
    noise = NoiseSource(config.noise, scene.shape, len(kernels)) if config.noise else None
    buf = np.empty(filtered.shape[1:])
    tmp = np.empty_like(buf)
    for t0, t1 in scene.blocks(block_steps):
        f, a = scene.frame_weights(t0, t1)
        dark = (
            orbit_receptive_sums(noise.dark_current(t1 - t0), kernels)
            if noise is not None else None
        )
        for b in range(t1 - t0):
            if a[b] == 0.0:
                drive = filtered[f[b]]
            else:
                np.multiply(filtered[f[b]], 1.0 - a[b], out=buf)
                np.multiply(filtered[f[b] + 1], a[b], out=tmp)
                buf += tmp
                drive = buf
            if dark is not None:
                np.add(drive, dark[b], out=buf)
                drive = buf
            yield t0 + b, drive


class Integrator:
    """The per-step integrate / compare / fire / reset state of ``S x H x W`` accumulators.

    ``thresholds`` is ``(S, H, W)``; ``signed`` models fire -1 at ``acc <= -thr``.
    """

    def __init__(self, thresholds: np.ndarray, signed: bool, reset: str):
        self.thr = np.ascontiguousarray(thresholds, dtype=np.float64)
        self.neg_thr = -self.thr
        self.signed = signed
        self.reset = reset
        self.acc = np.zeros_like(self.thr)
        self._pos = np.empty(self.thr.shape, dtype=bool)
        self._neg = np.empty(self.thr.shape, dtype=bool)
        self._fired = np.empty(self.thr.shape, dtype=bool)
        # +1 wins where a threshold is 0 and both comparisons hold.
        self._zero_thr = bool(np.any(self.thr == 0))

    def step(self, drive: np.ndarray, out: np.ndarray) -> None:
        """Integrate one step's ``drive (S, H, W)`` and write spikes into ``out (S, H, W)
        int8``."""
        acc = self.acc
        acc += drive
        if not self.signed:
            fired = out.view(bool)  # int8 0/1 and bool share a layout: compare in place
            np.greater_equal(acc, self.thr, out=fired)
            if self.reset == "zero":
                np.copyto(acc, 0.0, where=fired)
            else:
                np.subtract(acc, self.thr, out=acc, where=fired)
            return
        pos, neg = self._pos, self._neg
        np.greater_equal(acc, self.thr, out=pos)
        np.less_equal(acc, self.neg_thr, out=neg)
        if self._zero_thr:
            neg &= ~pos
        np.subtract(pos.view(np.int8), neg.view(np.int8), out=out)
        if self.reset == "zero":
            np.logical_or(pos, neg, out=self._fired)
            np.copyto(acc, 0.0, where=self._fired)
        else:
            np.subtract(acc, self.thr, out=acc, where=pos)
            np.add(acc, self.thr, out=acc, where=neg)


def sample(
    scene: Scene,
    config: SamplerConfig,
    block_steps: int = DEFAULT_BLOCK_STEPS,
    progress: bool = False,
    engine: str = "fused",
) -> SpikeTrain:
    """Run a float sampler over a whole scene.

    Returns a :class:`SpikeTrain` with ``spikes (T, S, H, W) int8`` (S = 1 for FSM).
    ``engine`` is ``"fused"`` (numba, default) or ``"numpy"`` (the reference); both give
    the same spikes. For long runs use :func:`rvsm.model.sampling.stream.stream_float`.
    """
    if engine not in ENGINES:
        raise RvsmError(f"engine must be one of {ENGINES}, got {engine!r}")
    if engine == "fused":
        from rvsm.model.sampling.stream import ArraySink, stream_float

        sink = ArraySink()
        train = stream_float(scene, config, sink, progress=progress)
        train.spikes = sink.spikes
        return train
    spec = config.spec
    thresholds = accumulator_thresholds(config, scene.shape)
    integrator = Integrator(thresholds, spec.signed, config.reset)
    require_spike_memory(scene, spec.num_scales)
    spikes = np.zeros((scene.num_steps, spec.num_scales) + scene.shape, dtype=np.int8)
    bar = progress_bar(scene.num_steps, f"{spec.name} {scene.name}", progress)
    for t, drive in iter_step_drives(scene, config, block_steps):
        integrator.step(drive, spikes[t])
        bar.update(1)
    bar.close()
    return SpikeTrain(spikes, thresholds, config, sampling_meta(scene, config))


def sampling_meta(scene: Scene, config: SamplerConfig) -> dict:
    """Metadata needed to reproduce a spike train (goes into the spike file's ``meta``):
    the scene's :meth:`~rvsm.model.scene.scene.Scene.meta`, its name, steps and the sampler."""
    return {
        "kind": "float",
        "scene": scene.name,
        **scene.meta(),
        "num_steps": scene.num_steps,
        "phis": [float(v) for v in config.phis],
        **config.to_dict(),
    }
