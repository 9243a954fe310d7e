"""Paper Table 1 / Fig. 6: quality of every model on the built-in scenes.

Functions here compute and return data, text and matplotlib figures; the CLI
(:mod:`rvsm.sim.cli.studies`) writes them to disk atomically.
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from matplotlib.figure import Figure

from rvsm.model.decode.evaluation import evaluate_spikes, reconstruct_for_display, scored_steps
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES, model_spec
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import DEFAULT_PHI, SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene import library as scene_library
from rvsm.model.scene.scene import Scene
from rvsm.sim.studies.labels import column_label, method_label
from rvsm.sim.studies.timing import compile_float_engine

TABLE_MODELS: tuple[str, ...] = MODEL_NAMES
FIG6_CLEAN: tuple[str, ...] = ("fsm", "gauss1", "dog3")
FIG6_NOISY: tuple[str, ...] = ("fsm", "gauss4", "dog4")
METRICS = ("mse", "psnr", "ssim")
_BETTER = {"mse": min, "psnr": max, "ssim": max}
_DECIMALS = {"mse": 2, "psnr": 2, "ssim": 3}


@dataclass
class TableResult:
    """Rows of the quality table and the images of the Fig. 6-style figure.

    ``rows``: one dict per (scene, noisy, model) with mse/psnr/ssim, num_scored, warmup,
    method, seconds. ``truth[scene]`` and ``display[(scene, noisy, model)]`` are
    ``(H, W)`` images at ``display_step[scene]``.
    """

    scenes: list[str]
    models: list[str]
    rows: list[dict] = field(default_factory=list)
    truth: dict = field(default_factory=dict)
    display: dict = field(default_factory=dict)
    display_step: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    seconds: float = 0.0


def load_scenes(
    names: Sequence[str] | None,
    size: tuple[int, int],
    num_frames: int,
    steps_per_frame: int,
) -> list[Scene]:
    """Built-in scenes (``rvsm.model.scene.library``) at the given size and length."""
    chosen = list(names) if names else list(scene_library.SCENE_NAMES)
    unknown = [n for n in chosen if n not in scene_library.SCENE_NAMES]
    if unknown:
        raise RvsmError(
            f"unknown scene(s) {', '.join(unknown)}; choose from "
            f"{', '.join(scene_library.SCENE_NAMES)}"
        )
    return [
        scene_library.builtin_scene(
            n, size=size, num_frames=num_frames, steps_per_frame=steps_per_frame
        )
        for n in chosen
    ]


def run_table(
    scenes: Sequence[Scene],
    seed: int = 0,
    phi: float = DEFAULT_PHI,
    models: Sequence[str] = TABLE_MODELS,
    noise_k: float = 1.0,
    progress: bool = False,
) -> TableResult:
    """Sample every scene with every model, without and with noise, and score it.

    Noise is ``NoiseParams(k=noise_k, seed=seed)`` (same dark current and fixed pattern for
    every model). Reconstruction: TFI for FSM, the RVSM adjoint otherwise; one gain per
    frame; scored on original-frame steps after the warm-up (:mod:`rvsm.model.decode.evaluation`).
    """
    from tqdm.auto import tqdm

    models = [model_spec(m).name for m in models]
    result = TableResult(
        scenes=[s.name for s in scenes],
        models=models,
        settings={"seed": seed, "phi": phi, "noise_k": noise_k},
    )
    shown = set(FIG6_CLEAN) | set(FIG6_NOISY)
    total = len(scenes) * 2 * len(models)
    start = time.perf_counter()
    with tqdm(total=total, desc="rvsm table", unit="run", disable=not progress) as bar:
        for scene in scenes:
            steps = scored_steps(scene, phi)
            show = int(steps[len(steps) // 2])
            result.display_step[scene.name] = show
            result.truth[scene.name] = scene.brightness(show, show + 1)[0]
            for noisy in (False, True):
                noise = NoiseParams(k=noise_k, seed=seed) if noisy else None
                for model in models:
                    bar.set_postfix_str(f"{column_label(scene.name, noisy)} {model}")
                    config = SamplerConfig(model=model, phi=phi, noise=noise)
                    compile_float_engine(config)  # seconds exclude numba's first compile
                    t0 = time.perf_counter()
                    train = sample(scene, config)
                    scores = evaluate_spikes(train.spikes, scene, model, config.phis)
                    if model in shown:
                        _, img = reconstruct_for_display(
                            train.spikes, scene, model, config.phis, [show]
                        )
                        result.display[(scene.name, noisy, model)] = img[0]
                    del train
                    result.rows.append(
                        {
                            "scene": scene.name,
                            "noise": noisy,
                            "model": model,
                            **scores,
                            "seconds": time.perf_counter() - t0,
                        }
                    )
                    bar.update(1)
    result.seconds = time.perf_counter() - start
    return result


def _lookup(result: TableResult) -> dict:
    return {(r["scene"], r["noise"], r["model"]): r for r in result.rows}


def _fmt(value: float, metric: str) -> str:
    if math.isinf(value):
        return "inf"
    return f"{value:.{_DECIMALS[metric]}f}"


def table_markdown(result: TableResult) -> str:
    """Table-1-style markdown: one block per metric, rows = methods, columns = scene and
    scene(N); the best value of each column in bold (lowest MSE, highest PSNR/SSIM)."""
    rows = _lookup(result)
    columns = [(s, n) for s in result.scenes for n in (False, True)]
    header = ["Metric", "Method"] + [column_label(s, n) for s, n in columns]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for metric in METRICS:
        best = {}
        for col in columns:
            vals = [rows[col + (m,)][metric] for m in result.models if col + (m,) in rows]
            best[col] = _BETTER[metric](vals) if vals else None
        for i, model in enumerate(result.models):
            cells = [metric.upper() if i == 0 else "", method_label(model)]
            for col in columns:
                row = rows.get(col + (model,))
                if row is None:
                    cells.append("-")
                    continue
                text = _fmt(row[metric], metric)
                cells.append(f"**{text}**" if row[metric] == best[col] else text)
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def table_csv(result: TableResult) -> str:
    """CSV text, one line per run: scene, noise, model, method, mse, psnr, ssim,
    num_scored, warmup, seconds."""
    buf = io.StringIO()
    fields = ["scene", "noise", "model", "method", "mse", "psnr", "ssim", "num_scored",
              "warmup", "seconds"]
    writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for row in result.rows:
        writer.writerow({k: row[k] for k in fields})
    return buf.getvalue()


def table_figure(result: TableResult) -> Figure:
    """Fig. 6-style grid: per scene (row) the truth, FSM / One Gauss / Three DoG without
    noise and FSM / Four Gauss / Four DoG with noise, all at the scene's display step."""
    cols = [("Ground truth", None)] + [(f"{method_label(m)}", (False, m)) for m in FIG6_CLEAN]
    cols += [(f"{method_label(m)} (N)", (True, m)) for m in FIG6_NOISY]
    n_rows = max(1, len(result.scenes))
    h, w = next(iter(result.truth.values())).shape if result.truth else (1, 1)
    cell = 1.8
    fig = Figure(figsize=(cell * len(cols), cell * n_rows * h / w + 0.4), dpi=110)
    axes = fig.subplots(n_rows, len(cols), squeeze=False)
    for r, scene in enumerate(result.scenes):
        for c, (title, key) in enumerate(cols):
            ax = axes[r, c]
            ax.set_xticks([])
            ax.set_yticks([])
            img = result.truth[scene] if key is None else result.display.get((scene,) + key)
            if img is not None:
                ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
            if r == 0:
                ax.set_title(title, fontsize=8)
            if c == 0:
                ax.set_ylabel(f"{scene}\nt={result.display_step[scene]}", fontsize=8)
    fig.subplots_adjust(left=0.06, right=0.99, top=0.93, bottom=0.01, wspace=0.03,
                        hspace=0.05)
    return fig
