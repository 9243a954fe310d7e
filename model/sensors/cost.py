"""What quantisation costs: fixed twin against the float model on the same scene (SPEC 5).

Both run on the same scene with the same seed and noise, the float model being the one
the point's sensor approximates (:attr:`~.capabilities.Sensor.float_of_point`: the
sampler of ``point.sampler_config()``, or for the event sensor
:func:`~rvsm.model.events.twin.sample_events` of ``point.event_config()``), and both
outputs are scored by the sensor's decoder (:attr:`~.capabilities.Sensor.evaluate`:
:func:`~rvsm.model.decode.evaluation.evaluate_spikes` with the nominal float thresholds,
or :func:`~rvsm.model.events.reconstruction.evaluate_events`, the twin's events decoded
with its own integer references and contrasts). It sits above the fixed twin and the
sensors it combines.

Spike agreement (:func:`spike_agreement`): over every (step, scale, pixel) where either
model fired, the fraction where both fired the same spike (+1 or -1), i.e.
``|fixed == float != 0| / |fixed != 0 or float != 0|``; 1.0 when neither fired.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.twin import fit_point, simulate_fixed
from rvsm.model.kinds.sensor_kind import sensor_kind
from rvsm.model.scene.scene import Scene
from rvsm.model.sensors.registry import DEFAULT_SENSOR, sensor_of
from rvsm.model.spikes.source import array_source


def spike_agreement(fixed: np.ndarray, float_: np.ndarray) -> dict:
    """Agreement of two ``(T, S, H, W)`` spike arrays.

    Returns ``agreement`` (see the module docstring), ``per_scale`` (list, same measure
    per scale), ``identical_entries`` (fraction of all entries equal, zeros included) and
    the spike counts ``spikes_fixed`` / ``spikes_float``.
    """
    a, b = np.asarray(fixed), np.asarray(float_)
    if a.shape != b.shape:
        raise ValueError(f"spike arrays differ in shape: {a.shape} vs {b.shape}")
    fired = (a != 0) | (b != 0)
    same = (a == b) & (b != 0)
    per_fired = fired.sum(axis=(0, 2, 3))
    per_same = same.sum(axis=(0, 2, 3))
    return {
        "agreement": _ratio(int(per_same.sum()), int(per_fired.sum())),
        "per_scale": [_ratio(int(s), int(f)) for s, f in zip(per_same, per_fired, strict=True)],
        "identical_entries": float(np.mean(a == b)) if a.size else 1.0,
        "spikes_fixed": int(np.count_nonzero(a)),
        "spikes_float": int(np.count_nonzero(b)),
    }


def _ratio(num: int, den: int) -> float:
    return 1.0 if den == 0 else num / den


def quantisation_cost(
    scene: Scene,
    point: DesignPoint,
    method: str = "auto",
    match: str = "gain",
    progress: bool = False,
) -> dict:
    """Run float and fixed on ``scene`` and compare them (and both with ground truth).

    Returns a JSON-ready dict: ``agreement``, ``agreement_per_scale``,
    ``identical_entries``, ``spikes_float``, ``spikes_fixed``, ``psnr_float``,
    ``psnr_fixed``, ``psnr_cost`` (float minus fixed, dB), ``ssim_float``, ``ssim_fixed``,
    ``ssim_cost``, ``mse_float``, ``mse_fixed``, ``saturated`` (per scale), ``method``,
    ``scene``, ``model``, ``height``, ``width``, ``steps``, ``design_point``.
    """
    point = fit_point(scene, point)
    sensor = sensor_of(point.kind)
    fix = simulate_fixed(scene, point, progress=progress, ranges=False)
    flt, flt_meta = sensor.float_of_point(scene, point, progress)
    agree = spike_agreement(fix.spikes, flt)
    ev_float = sensor.evaluate(array_source(flt, flt_meta), scene, method=method, match=match)
    ev_fixed = sensor.evaluate(array_source(fix.spikes, fix.meta), scene, method=method,
                               match=match)
    return {
        "scene": scene.name,
        "model": point.model,
        "sensor": point.sensor,
        "height": point.height,
        "width": point.width,
        "steps": scene.num_steps,
        "agreement": agree["agreement"],
        "agreement_per_scale": agree["per_scale"],
        "identical_entries": agree["identical_entries"],
        "spikes_float": agree["spikes_float"],
        "spikes_fixed": agree["spikes_fixed"],
        "psnr_float": float(ev_float["psnr"]),
        "psnr_fixed": float(ev_fixed["psnr"]),
        "psnr_cost": float(ev_float["psnr"] - ev_fixed["psnr"]),
        "ssim_float": float(ev_float["ssim"]),
        "ssim_fixed": float(ev_fixed["ssim"]),
        "ssim_cost": float(ev_float["ssim"] - ev_fixed["ssim"]),
        "mse_float": float(ev_float["mse"]),
        "mse_fixed": float(ev_fixed["mse"]),
        "method": ev_fixed["method"],
        "saturated": [int(v) for v in fix.stats.saturated],
        "design_point": point.to_dict(),
    }


def format_cost(result: dict) -> str:
    """Human-readable summary of :func:`quantisation_cost`."""
    per = ", ".join(f"{100 * a:.2f}%" for a in result["agreement_per_scale"])
    return "\n".join([
        f"quantisation cost: {result['model']}"
        f"{sensor_kind(result.get('sensor', DEFAULT_SENSOR)).suffix} on {result['scene']} "
        f"({result['height']}x{result['width']}, {result['steps']} steps, "
        f"{result['method']} reconstruction)",
        f"spike agreement  {100 * result['agreement']:.2f}% of spikes (per scale: {per}); "
        f"{100 * result['identical_entries']:.3f}% of entries identical",
        f"spikes           float {result['spikes_float']}, fixed {result['spikes_fixed']}",
        f"PSNR             float {result['psnr_float']:.3f} dB, fixed "
        f"{result['psnr_fixed']:.3f} dB, cost {result['psnr_cost']:+.3f} dB",
        f"SSIM             float {result['ssim_float']:.4f}, fixed {result['ssim_fixed']:.4f}, "
        f"cost {result['ssim_cost']:+.4f}",
        f"saturated        {result['saturated']} accumulator-steps per scale",
    ])
