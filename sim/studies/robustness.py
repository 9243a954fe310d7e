"""Paper Fig. 8 (section 4.3): noise spikes of a black scene against noise intensity k.

Functions here compute and return data, text and matplotlib figures; the CLI
(:mod:`rvsm.sim.cli.studies`) writes them to disk atomically.
"""

from __future__ import annotations

import csv
import io
import time
from collections.abc import Sequence
from dataclasses import dataclass

from matplotlib.figure import Figure

from rvsm.model.decode.metrics import robustness_indices
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import model_spec
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import DEFAULT_PHI, SamplerConfig
from rvsm.model.sampling.thresholds import (
    DEFAULT_CALIBRATION_SCENE,
    THRESHOLD_RULES,
    calibration_thresholds,
)
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.library import black_scene
from rvsm.sim.studies.labels import method_label

ROBUST_MODELS: tuple[str, ...] = ("fsm", "dog1", "dog2", "dog3", "dog4", "gauss4")
DEFAULT_KS: tuple[float, ...] = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0)


@dataclass
class RobustnessResult:
    """One row per (k, model): ``k, model, ass, asas, asass`` (list, one per scale)."""

    rows: list[dict]
    size: tuple[int, int]
    num_steps: int
    seed: int
    seconds: float = 0.0


def run_robustness(
    ks: Sequence[float] = DEFAULT_KS,
    size: tuple[int, int] = (100, 100),
    num_steps: int = 1000,
    seed: int = 0,
    phi: float = DEFAULT_PHI,
    models: Sequence[str] = ROBUST_MODELS,
    progress: bool = False,
    thresholds: str = "equal",
    calibration_scene: str = DEFAULT_CALIBRATION_SCENE,
) -> RobustnessResult:
    """Paper section 4.3: spikes of a black scene under noise of intensity ``k``.

    Every model sees ``NoiseParams(k, seed)``; returns ASS, ASAS and ASASS per run. With
    ``thresholds="response"`` each RVSM model's per-scale thresholds are those of the
    response rule on the built-in ``calibration_scene`` at ``size`` (a black scene has no
    response of its own; :func:`rvsm.model.sampling.thresholds.calibration_thresholds`).
    """
    from tqdm.auto import tqdm

    if thresholds not in THRESHOLD_RULES:
        raise RvsmError(f"unknown threshold rule {thresholds!r}; choose one of "
                        f"{THRESHOLD_RULES}")

    scene = black_scene(size, num_steps)
    models = [model_spec(m).name for m in models]
    rows = []
    start = time.perf_counter()
    with tqdm(total=len(ks) * len(models), desc="rvsm robustness", unit="run",
              disable=not progress) as bar:
        for k in ks:
            for model in models:
                scale_phi = None
                if thresholds == "response" and model_spec(model).family != "fsm":
                    scale_phi = calibration_thresholds(calibration_scene, model, phi,
                                                       tuple(size))
                config = SamplerConfig(model=model, phi=phi, scale_phi=scale_phi,
                                       noise=NoiseParams(k=k, seed=seed))
                idx = robustness_indices(sample(scene, config).spikes)
                rows.append({"k": float(k), "model": model, **idx})
                bar.update(1)
    return RobustnessResult(rows, tuple(size), num_steps, seed, time.perf_counter() - start)


def robustness_csv(result: RobustnessResult) -> str:
    """CSV text: k, model, ass, asas, asass_1..asass_4 (empty past the model's scales)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["k", "model", "ass", "asas", "asass_1", "asass_2", "asass_3", "asass_4"])
    for row in result.rows:
        per = [f"{v:.10g}" for v in row["asass"]] + [""] * (4 - len(row["asass"]))
        writer.writerow([f"{row['k']:g}", row["model"], f"{row['ass']:.10g}",
                         f"{row['asas']:.10g}"] + per)
    return buf.getvalue()


def robustness_figure(result: RobustnessResult) -> Figure:
    """Fig. 8: (a) ASS vs k, (b) ASAS vs k per model, (c) ASASS per scale vs k (RVSM
    models with the most scales; FSM as reference)."""
    fig = Figure(figsize=(13, 3.8), dpi=110)
    ax_a, ax_b, ax_c = fig.subplots(1, 3)
    models = list(dict.fromkeys(r["model"] for r in result.rows))
    for model in models:
        rows = [r for r in result.rows if r["model"] == model]
        ks = [r["k"] for r in rows]
        style = "--" if model.startswith("gauss") else "-"
        ax_a.plot(ks, [r["ass"] for r in rows], style, marker="o", ms=3,
                  label=method_label(model))
        ax_b.plot(ks, [r["asas"] for r in rows], style, marker="o", ms=3,
                  label=method_label(model))
    for model in models:
        rows = [r for r in result.rows if r["model"] == model]
        ks = [r["k"] for r in rows]
        spec = model_spec(model)
        if spec.family == "fsm":
            ax_c.plot(ks, [r["asass"][0] for r in rows], "k:", marker="o", ms=3, label="FSM")
        elif spec.num_scales == 4:
            style = "--" if spec.family == "gauss" else "-"
            for s in range(4):
                ax_c.plot(ks, [r["asass"][s] for r in rows], style, marker="o", ms=3,
                          label=f"{method_label(model)} scale {s + 1} ({spec.scales[s]})")
    h, w = result.size
    for ax, title, ylabel in (
        (ax_a, "(a) ASS", "I1: spikes per step"),
        (ax_b, "(b) ASAS", "I2: spikes per step per accumulator"),
        (ax_c, "(c) ASASS", "I3: spikes per step per pixel, one scale"),
    ):
        ax.set_title(f"{title}  (black {h}x{w}, T={result.num_steps})", fontsize=9)
        ax.set_xlabel("noise intensity k")
        ax.set_ylabel(ylabel, fontsize=8)
        if any(y > 0 for line in ax.get_lines() for y in line.get_ydata()):
            ax.set_yscale("log", nonpositive="mask")  # nothing to show on a log axis else
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    fig.tight_layout()
    return fig
