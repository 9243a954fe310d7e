"""Image quality of one design point, and what its quantisation and the chip cost a user.

On every scene, with noise off and on, three runs of the same scene (same seed) are
scored against its ground truth by the sensor's own decoder (reconstruction, brightness
matching, warm-up skip, PSNR/SSIM: :attr:`~rvsm.model.sensors.capabilities.Sensor.evaluate`):

- the point's **fixed twin** and its **own float model** -- both from
  :func:`~rvsm.model.sensors.cost.quantisation_cost`, the sweep's PSNR cost;
- the **float model of the default design point** (dog4,
  :func:`~rvsm.model.fixed.design_point.default_design_point`) under the point's noise
  (same ``k`` or preset, same seed).

Costs (dB of PSNR; SSIM likewise): ``quantisation = own float - twin`` (what the fixed
point costs) and ``chip = default float - twin`` (what choosing this chip instead of the
default float model costs a user). For the default point itself both are the same.

Noise "on" uses the point's noise settings (``noise_params()``: its ``k`` or preset and its
seed); "off" the same point with ``noise.enabled = false``. When the point's own float
model is the default's (same sampler), its run is not repeated: the scores are the same.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene

__all__ = ["DEFAULT_FRAMES", "DEFAULT_STEPS_PER_FRAME", "PointQuality", "QualityRow",
           "better_or_worse", "noisy_point", "reconstructions", "run_point_quality",
           "scene_quality"]

#: Frames (and steps per frame) of the study by default: 41 frames x 10 = 400 steps, as
#: ``rvsm table`` and ``sweeps/default-check.toml``.
DEFAULT_FRAMES = 41
DEFAULT_STEPS_PER_FRAME = 10
#: The three models scored, in table order.
MODELS = ("twin", "float", "default_float")


@dataclass(frozen=True)
class QualityRow:
    """One scene at one noise setting: PSNR (dB) and SSIM of the twin, the point's own
    float model and the default point's float model, and the run's wall ``seconds``."""

    scene: str
    noise: bool
    psnr_twin: float
    ssim_twin: float
    psnr_float: float
    ssim_float: float
    psnr_default_float: float
    ssim_default_float: float
    seconds: float = 0.0

    @property
    def quantisation_cost_db(self) -> float:
        """Own float minus twin, dB: what the fixed point costs."""
        return self.psnr_float - self.psnr_twin

    @property
    def chip_cost_db(self) -> float:
        """Default (dog4) float minus twin, dB: what the chip costs a user."""
        return self.psnr_default_float - self.psnr_twin

    @property
    def quantisation_cost_ssim(self) -> float:
        """Own float minus twin, SSIM."""
        return self.ssim_float - self.ssim_twin

    @property
    def chip_cost_ssim(self) -> float:
        """Default (dog4) float minus twin, SSIM."""
        return self.ssim_default_float - self.ssim_twin

    def to_dict(self) -> dict[str, Any]:
        """Fields and the four costs."""
        return {**dataclasses.asdict(self),
                "quantisation_cost_db": self.quantisation_cost_db,
                "chip_cost_db": self.chip_cost_db,
                "quantisation_cost_ssim": self.quantisation_cost_ssim,
                "chip_cost_ssim": self.chip_cost_ssim}


@dataclass(frozen=True)
class PointQuality:
    """The study of one point: ``rows`` per scene and noise setting, at ``size`` (H, W)
    with ``frames`` x ``steps_per_frame``; ``point`` the design point as a flat dict
    (:meth:`DesignPoint.to_dict`), ``seconds`` the whole run."""

    point: dict[str, Any]
    size: tuple[int, int]
    frames: int
    steps_per_frame: int
    rows: tuple[QualityRow, ...]
    seconds: float = 0.0
    command: str = ""
    method: str = "auto"
    match: str = "gain"
    default_point: dict[str, Any] = field(default_factory=dict)

    @property
    def steps(self) -> int:
        """Simulated steps per run."""
        return (self.frames - 1) * self.steps_per_frame

    def rows_with(self, noise: bool) -> list[QualityRow]:
        """The rows at one noise setting, scene order kept."""
        return [r for r in self.rows if r.noise == noise]

    def to_json(self) -> str:
        """One JSON object (``rvsm quality --json``): every field, rows with their costs."""
        d = {k: v for k, v in dataclasses.asdict(self).items() if k != "rows"}
        d["size"] = list(self.size)
        d["steps"] = self.steps
        d["rows"] = [r.to_dict() for r in self.rows]
        return json.dumps(d, indent=1)

    @classmethod
    def from_json(cls, text: str, source: str = "quality result") -> PointQuality:
        """Read :meth:`to_json` back; :class:`RvsmError` naming ``source`` otherwise."""
        try:
            d = json.loads(text)
            names = {f.name for f in dataclasses.fields(QualityRow)}
            rows = tuple(QualityRow(**{k: v for k, v in r.items() if k in names})
                         for r in d["rows"])
            h, w = (int(v) for v in d["size"])
            return cls(point=dict(d["point"]), size=(h, w), frames=int(d["frames"]),
                       steps_per_frame=int(d["steps_per_frame"]), rows=rows,
                       seconds=float(d.get("seconds", 0.0)), command=str(d.get("command", "")),
                       method=str(d.get("method", "auto")), match=str(d.get("match", "gain")),
                       default_point=dict(d.get("default_point") or {}))
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise RvsmError(f"{source}: not an rvsm quality --json result ({exc}); make it "
                            "with rvsm quality POINT --json") from None

    def csv(self) -> str:
        """One line per row: scene, noise, the six scores and the four costs."""
        head = ("scene,noise,psnr_twin,psnr_float,psnr_default_float,quantisation_cost_db,"
                "chip_cost_db,ssim_twin,ssim_float,ssim_default_float,"
                "quantisation_cost_ssim,chip_cost_ssim")
        lines = [head]
        for r in self.rows:
            lines.append(",".join([r.scene, "on" if r.noise else "off"] + [
                f"{v:.4f}" for v in (r.psnr_twin, r.psnr_float, r.psnr_default_float,
                                     r.quantisation_cost_db, r.chip_cost_db)] + [
                f"{v:.5f}" for v in (r.ssim_twin, r.ssim_float, r.ssim_default_float,
                                     r.quantisation_cost_ssim, r.chip_cost_ssim)]))
        return "\n".join(lines) + "\n"

    def markdown(self, noise: bool) -> list[str]:
        """A Markdown table of the rows at one noise setting, with a mean row."""
        rows = self.rows_with(noise)
        lines = ["| scene | PSNR twin | own float | dog4 float | twin against own float | "
                 "chip against dog4 float | SSIM twin | own float | dog4 float |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(_md_row(r.scene, [r.psnr_twin, r.psnr_float, r.psnr_default_float,
                                           r.quantisation_cost_db, r.chip_cost_db,
                                           r.ssim_twin, r.ssim_float, r.ssim_default_float]))
        if rows:
            cols = np.mean([[r.psnr_twin, r.psnr_float, r.psnr_default_float,
                             r.quantisation_cost_db, r.chip_cost_db, r.ssim_twin,
                             r.ssim_float, r.ssim_default_float] for r in rows], axis=0)
            lines.append(_md_row("**mean**", list(cols)))
        return lines

    def steps_text(self) -> str:
        """``400 steps (40 frame intervals x 10 steps; 41 frames)``: the steps are
        ``(frames - 1) x steps_per_frame``."""
        return (f"{self.steps} steps ({self.frames - 1} frame intervals x "
                f"{self.steps_per_frame} steps; {self.frames} frames)")

    def summary(self) -> str:
        """Human-readable lines: the two tables and the run's size and time."""
        h, w = self.size
        out = [f"image quality of {self.point.get('model')} ({self.point.get('sensor')}) "
               f"at {h}x{w}, {self.steps_text()}, seed {self.point.get('seed')}; PSNR in "
               "dB; the twin against its own float model (what the fixed point costs) and "
               "against the default dog4 float model (what the chip costs a user)"]
        for noise in (False, True):
            if self.rows_with(noise):
                out += ["", f"noise {'on' if noise else 'off'}:", *self.markdown(noise)]
        out += ["", f"{len(self.rows)} runs in {self.seconds:.0f} s"]
        return "\n".join(out)


def better_or_worse(gain_db: float, digits: int = 3) -> str:
    """``better by X`` (``gain_db > 0``), ``worse by X`` or ``equal`` at ``digits``."""
    shown = f"{abs(gain_db):.{digits}f}"
    if float(shown) == 0:
        return "equal"
    return f"{'better' if gain_db > 0 else 'worse'} by {shown}"


def _md_row(name: str, values: Sequence[float]) -> str:
    """Values: three PSNRs, the two costs (float - twin, dB: shown as the twin better
    or worse by), three SSIMs."""
    psnr = [f"{v:.2f}" for v in values[:3]] + [better_or_worse(-v) for v in values[3:5]]
    ssim = [f"{v:.4f}" for v in values[5:]]
    return f"| {name} | " + " | ".join(psnr + ssim) + " |"


def noisy_point(point: DesignPoint, noise: bool, like: DesignPoint | None = None
                ) -> DesignPoint:
    """``point`` with noise on or off; with ``like``, ``point`` taking ``like``'s noise
    settings (``k``, preset, seed) so that both float models see the same noise."""
    src = like if like is not None else point
    return dataclasses.replace(point, noise=bool(noise), noise_k=src.noise_k, seed=src.seed,
                               noise_preset=src.noise_preset)


def _default_for(point: DesignPoint, scene: Scene) -> DesignPoint:
    """The default point at the scene's size with ``point``'s noise settings."""
    return noisy_point(default_design_point().with_size(*scene.shape), point.noise, point)


def scene_quality(scene: Scene, point: DesignPoint, method: str = "auto",
                  match: str = "gain") -> QualityRow:
    """The :class:`QualityRow` of ``point`` (noise as it says) on ``scene``."""
    from rvsm.model.sensors.cost import quantisation_cost
    from rvsm.model.sensors.registry import sensor_of
    from rvsm.model.spikes.source import array_source

    t0 = time.perf_counter()
    rec = quantisation_cost(scene, point, method=method, match=match)
    default = _default_for(point, scene)
    if _same_float_model(point, default):  # the same deterministic run: its scores
        psnr, ssim = rec["psnr_float"], rec["ssim_float"]
    else:
        sensor = sensor_of(default.kind)
        spikes, meta = sensor.float_of_point(scene, default, False)
        ev = sensor.evaluate(array_source(spikes, meta), scene, method=method, match=match)
        psnr, ssim = float(ev["psnr"]), float(ev["ssim"])
    return QualityRow(scene=str(scene.name), noise=bool(point.noise),
                      psnr_twin=rec["psnr_fixed"], ssim_twin=rec["ssim_fixed"],
                      psnr_float=rec["psnr_float"], ssim_float=rec["ssim_float"],
                      psnr_default_float=psnr, ssim_default_float=ssim,
                      seconds=time.perf_counter() - t0)


def _same_float_model(point: DesignPoint, default: DesignPoint) -> bool:
    """Whether ``point`` approximates the default point's float model itself (same
    sensor, same sampler: model, thresholds, reset, noise and seed), so that the float
    run of :func:`~rvsm.model.sensors.cost.quantisation_cost` is the default's."""
    return (point.kind == default.kind and point.shape == default.shape
            and point.sampler_config() == default.sampler_config())


def _load(name: str, size: tuple[int, int], frames: int, steps_per_frame: int) -> Scene:
    from rvsm.model.scene.loaders import load_scene

    return load_scene(name, size=size, num_frames=frames, steps_per_frame=steps_per_frame)


def run_point_quality(point: DesignPoint, scenes: Sequence[str] | None = None,
                      size: tuple[int, int] | None = None, frames: int = DEFAULT_FRAMES,
                      steps_per_frame: int = DEFAULT_STEPS_PER_FRAME,
                      noise: Sequence[bool] = (False, True), method: str = "auto",
                      match: str = "gain", progress: bool = False,
                      command: str = "") -> PointQuality:
    """The study of ``point`` (module docstring) on ``scenes`` (default every built-in
    scene) at ``size`` (default the point's), noise off and/or on; progress lines on
    stderr when ``progress``."""
    from rvsm.model.scene.library import SCENE_NAMES

    if frames < 2:
        raise RvsmError(f"frames must be >= 2 (steps = (frames - 1) x steps per frame), "
                        f"got {frames}")
    if steps_per_frame < 1:
        raise RvsmError(f"steps per frame must be >= 1, got {steps_per_frame}")
    names = list(scenes) if scenes else list(SCENE_NAMES)
    settings = list(dict.fromkeys(bool(n) for n in noise))
    if not settings:
        raise RvsmError("choose at least one noise setting (off, on)")
    size = tuple(size) if size is not None else point.shape
    t0 = time.perf_counter()
    rows = []
    total = len(names) * len(settings)
    for name in names:
        scene = _load(name, size, frames, steps_per_frame)
        for on in settings:
            row = scene_quality(scene, noisy_point(point, on), method, match)
            rows.append(row)
            if progress:
                print(f"rvsm quality: {len(rows)}/{total} {name} noise "
                      f"{'on' if on else 'off'}: twin {row.psnr_twin:.2f} dB, own float "
                      f"{row.psnr_float:.2f}, dog4 float {row.psnr_default_float:.2f} "
                      f"({row.seconds:.1f} s)", file=sys.stderr, flush=True)
    return PointQuality(point=point.to_dict(), size=(int(size[0]), int(size[1])),
                        frames=int(frames), steps_per_frame=int(steps_per_frame),
                        rows=tuple(rows), seconds=time.perf_counter() - t0, command=command,
                        method=method, match=match,
                        default_point=default_design_point().to_dict())


def reconstructions(point: DesignPoint, scene: Scene, step: int | None = None,
                    method: str = "auto", match: str = "gain"
                    ) -> tuple[int, dict[str, np.ndarray]]:
    """``(step, images)``: the ground truth and the brightness-matched reconstructions of
    the default dog4 float model, the point's own float model and its fixed twin (noise as
    ``point`` says), each ``(H, W) float64`` in [0, 255], at ``step`` (default the last
    scored step of the twin). Spike-camera points only (the event sensor decodes
    differently): :class:`RvsmError` otherwise."""
    from rvsm.model.decode.evaluation import reconstruct_for_display, scored_steps
    from rvsm.model.fixed.twin import fit_point, simulate_fixed
    from rvsm.model.sensors.registry import sensor_of

    point = fit_point(scene, point)
    default = _default_for(point, scene)
    if point.kind != default.kind:
        raise RvsmError(f"reconstruction pictures are drawn for the spike camera; this "
                        f"point's sensor is {point.sensor}")
    fix = simulate_fixed(scene, point, ranges=False)
    if step is None:
        step = int(scored_steps(scene, fix.meta["phis"])[-1])
    if not 0 <= step < scene.num_steps:
        raise RvsmError(f"step {step} is outside the scene's 0..{scene.num_steps - 1}")
    runs = {"twin": (fix.spikes, fix.meta)}
    runs["float"] = sensor_of(point.kind).float_of_point(scene, point, False)
    runs["default_float"] = sensor_of(default.kind).float_of_point(scene, default, False)
    images: dict[str, np.ndarray] = {}
    for name in ("default_float", "float", "twin"):
        spikes, meta = runs[name]
        truth, recon = reconstruct_for_display(spikes, scene, meta["model"],
                                               np.asarray(meta["phis"], dtype=np.float64),
                                               [step], method, match)
        images.setdefault("truth", truth[0])
        images[name] = recon[0]
    return step, {k: images[k] for k in ("truth", "default_float", "float", "twin")}
