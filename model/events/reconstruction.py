"""Images from events (SPEC section 7): responses from the references and the event
counts, the RVSM least-squares inverse, ``exp(L_hat) - 1``, and their scores.

The sensor reports its references at the capture step, so ``R_hat(t) = R(0) + C_s *
(sum of events up to t)`` (``C_s`` the nominal per-scale contrast: a decoder knows no
pixel's gain); ``L_hat`` is the least-squares inverse of the receptive fields applied to
``R_hat`` (:func:`rvsm.model.decode.inverse.inverse_images`; the identity for the plain
DVS), the image ``exp(L_hat) - 1``, then the brightness matching and metrics of SPEC
section 4. An event list (:mod:`.event_list`) carries the references; the project's own
event files (the spike-file formats) do not, so they are regenerated from the scene and
the file's metadata (the same float model, dark current of step 0 included),
:func:`capture_references`. The fixed-point twin's events (their meta holds the design
point) are decoded with the integer references and the quantised contrasts, in log units
(:mod:`rvsm.model.fixed.event_references`), which the caller passes as ``reported``:
the event sensor's decoder, :mod:`rvsm.model.sensors.event_sensor`, above both packages.
Files are read chunk by chunk (memory: one chunk plus the running counts and the scored
steps' responses).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rvsm.model.decode.inverse import inverse_images
from rvsm.model.decode.metrics import DATA_RANGE, image_metrics
from rvsm.model.decode.reconstruction import MATCH_MODES, match_brightness
from rvsm.model.events.config import EventConfig
from rvsm.model.events.numpy_engine import log_brightness
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.orbits import orbit_receptive_sums
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.source import SpikeSource

__all__ = ["capture_references", "config_from_meta", "evaluate_events", "event_images",
           "event_responses", "scored_event_steps"]


def config_from_meta(meta: dict) -> EventConfig:
    """The :class:`EventConfig` an event file's metadata records."""
    try:
        noise = meta.get("noise")
        return EventConfig(model=meta["model"], contrast=float(meta["contrast"]),
                           scale_contrast=(tuple(meta["scale_contrast"])
                                           if meta.get("scale_contrast") else None),
                           noise=NoiseParams(**noise) if noise else None)
    except (KeyError, TypeError, ValueError) as exc:
        raise RvsmError(f"the event file's meta does not describe an event sensor ({exc}); "
                        "re-run rvsm simulate --sensor dvs") from None


def capture_references(scene: Scene, config: EventConfig) -> np.ndarray:
    """The references ``(S, H, W) float64`` a sensor of ``config`` captures at step 0 of
    ``scene``: the receptive sums of the first step's log intensity."""
    spec = config.spec
    noise = (NoiseSource(config.noise, scene.shape, spec.num_scales)
             if config.noise is not None else None)
    return orbit_receptive_sums(log_brightness(scene, noise, 0, 1), spec.kernels())[0]


def scored_event_steps(scene: Scene) -> np.ndarray:
    """Steps scored: every step on an original frame after the capture step (step 0's
    response is the reference itself); the last step when there is none."""
    m = scene.steps_per_frame
    steps = np.arange(m, scene.num_steps, m, dtype=np.int64)
    return steps if steps.size else np.array([scene.num_steps - 1], dtype=np.int64)


def event_responses(source: SpikeSource, references: np.ndarray, contrasts: np.ndarray,
                    steps: np.ndarray, chunk_steps: int = 256) -> np.ndarray:
    """``R_hat (N, S, H, W)`` at ``steps`` (increasing): references plus ``contrasts (S,)``
    times the running event counts, the file read chunk by chunk."""
    steps = np.asarray(steps, dtype=np.int64)
    counts = np.zeros(source.shape[1:], dtype=np.int64)
    out = np.empty((len(steps),) + tuple(source.shape[1:]))
    c = np.asarray(contrasts, dtype=np.float64)[:, None, None]
    k = 0
    for t0 in range(0, source.num_steps, chunk_steps):
        if k == len(steps):
            break
        t1 = min(source.num_steps, t0 + chunk_steps)
        chunk = source.read(t0, t1)
        running = counts + np.cumsum(chunk, axis=0, dtype=np.int64)
        while k < len(steps) and steps[k] < t1:
            out[k] = references + c * running[steps[k] - t0]
            k += 1
        counts = running[-1]
    return out


def event_images(responses: np.ndarray, config: EventConfig) -> np.ndarray:
    """Images ``(N, H, W)``: ``exp(L_hat) - 1`` with ``L_hat`` the least-squares inverse
    of ``responses (N, S, H, W)`` (the plain DVS: the response itself)."""
    spec = config.spec
    if spec.num_scales == 1 and spec.kernels()[0].shape == (1, 1):
        log_hat = responses[:, 0]
    else:
        log_hat = inverse_images(responses, spec)
    return np.expm1(log_hat)


#: What a sensor reported at its capture step, from the scene and the file's meta:
#: ``(references (S, H, W), contrasts (S,))`` in log-intensity units.
Reported = Callable[[Scene, dict], tuple[np.ndarray, np.ndarray]]


def evaluate_events(source: SpikeSource, scene: Scene, match: str = "gain",
                    reported: Reported | None = None) -> dict:
    """Score an event file against ``scene``: ``{"mse", "psnr", "ssim", "num_scored",
    "method"}`` averaged over :func:`scored_event_steps` (SPEC sections 4 and 7).

    The references and contrasts are those the source reports (an event list), else
    ``reported(scene, meta)`` (the fixed-point twin's, required when the meta holds a
    design point), else the float model's (:func:`capture_references`)."""
    if match not in MATCH_MODES:
        raise RvsmError(f"unknown brightness match {match!r}; choose one of {MATCH_MODES}")
    config = config_from_meta(source.meta)
    spec = config.spec
    want = (scene.num_steps, spec.num_scales) + scene.shape
    if tuple(source.shape) != want:
        raise RvsmError(f"events {tuple(source.shape)} do not match scene {scene.name!r} "
                        f"and model {spec.name} (expected {want})")
    steps = scored_event_steps(scene)
    refs = getattr(source, "references", None)  # reported in an event list
    contrasts = getattr(source, "contrasts", None)
    if reported is None and source.meta.get("design_point") is not None and \
            (refs is None or contrasts is None):
        raise RvsmError("the fixed-point twin's events are decoded with its own references: "
                        "evaluate them with rvsm.model.sensors (rvsm evaluate)")
    if reported is not None:  # e.g. the fixed-point twin's events
        fixed_refs, fixed_contrasts = reported(scene, source.meta)
        refs = fixed_refs if refs is None else refs
        contrasts = fixed_contrasts if contrasts is None else contrasts
    if refs is None:
        refs = capture_references(scene, config)
    if contrasts is None:
        contrasts = config.contrasts
    responses = event_responses(source, refs, contrasts, steps)
    images = event_images(responses, config)
    truth = np.stack([scene.brightness(int(t), int(t) + 1)[0] for t in steps])
    recon = np.clip(match_brightness(images, truth, match), 0.0, DATA_RANGE)
    scores = image_metrics(recon, truth)
    method = "identity" if spec.name == "fsm" else "inverse"
    return {"mse": scores["mse"], "psnr": scores["psnr"], "ssim": scores["ssim"],
            "num_scored": int(len(steps)), "warmup": 0, "method": f"events-{method}"}
