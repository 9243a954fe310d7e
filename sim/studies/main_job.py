"""The main job on a built-in scene: what ``make demo`` runs.

FSM, ``dog4`` and ``gauss4`` with default noise sample one built-in scene; each writes
its spike file, a PNG of reconstructions beside ground truth, and a row of the metrics
table (markdown and CSV). Everything lands under one output folder.
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rvsm.model.decode.evaluation import evaluate_spikes, reconstruct_for_display, scored_steps
from rvsm.model.infra.atomic import atomic_path, write_text_atomic
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.npz import save_spikes
from rvsm.sim.studies.timing import compile_float_engine

DEMO_SCENE = "flyball"
DEMO_MODELS = ("fsm", "dog4", "gauss4")
# The flat RTL array is verified on a small window: Verilator builds grow with the array.
#: The RTL check of the demo: the streaming array (rtl/stream) at this size,
#: lanes and steps, spike for spike against the fixed twin.
DEMO_RTL_SIZE = (64, 96)
DEMO_RTL_LANES = 8
DEMO_RTL_STEPS = 40


@dataclass(frozen=True)
class DemoRow:
    """One model's demo result."""

    model: str
    spikes: int
    negative_spikes: int
    seconds: float
    mse: float
    psnr: float
    ssim: float


def run_float_demo(
    scene: Scene, out_dir: Path, models: tuple[str, ...] = DEMO_MODELS, seed: int = 0,
    progress: bool = True,
) -> list[DemoRow]:
    """Sample ``scene`` with each model under default noise; write spikes, PNGs and tables.

    Returns one :class:`DemoRow` per model. Files: ``<model>.npz``, ``<model>.png``,
    ``metrics.md``, ``metrics.csv`` in ``out_dir``.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for model in models:
        config = SamplerConfig(model=model, noise=NoiseParams(k=1.0, seed=seed))
        compile_float_engine(config)  # seconds exclude numba's first compile
        start = time.perf_counter()
        train = sample(scene, config, progress=progress)
        seconds = time.perf_counter() - start
        save_spikes(out_dir / f"{model}.npz", train.spikes, train.meta)
        scores = evaluate_spikes(train.spikes, scene, model, config.phis)
        _save_figure(train.spikes, scene, model, config.phis, out_dir / f"{model}.png")
        rows.append(DemoRow(model, int(np.count_nonzero(train.spikes)),
                            int((train.spikes < 0).sum()), seconds,
                            scores["mse"], scores["psnr"], scores["ssim"]))
    write_text_atomic(out_dir / "metrics.md", metrics_markdown(scene, rows))
    write_text_atomic(out_dir / "metrics.csv", metrics_csv(rows))
    return rows


def _save_figure(spikes, scene: Scene, model: str, phis, path: Path) -> None:
    from matplotlib.figure import Figure

    steps = scored_steps(scene, phis)
    picks = steps[np.linspace(0, steps.size - 1, min(3, steps.size)).astype(int)]
    truth, recon = reconstruct_for_display(spikes, scene, model, phis, picks)
    fig = Figure(figsize=(8, 2.6 * len(picks)))
    axes = fig.subplots(len(picks), 2, squeeze=False)
    for row, t in enumerate(picks):
        for col, (img, label) in enumerate(((truth[row], "ground truth"),
                                            (recon[row], f"{model} reconstruction"))):
            ax = axes[row, col]
            ax.imshow(img, cmap="gray", vmin=0, vmax=255)
            ax.set_title(f"{label}, step {int(t)}", fontsize=9)
            ax.axis("off")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")


def metrics_markdown(scene: Scene, rows: list[DemoRow]) -> str:
    """The demo's metrics as a markdown table."""
    h, w = scene.shape
    lines = [
        f"# Demo: `{scene.name}` ({h}x{w}, {scene.num_steps} steps), default noise (k=1)",
        "",
        "| model | spikes | negative | MSE | PSNR (dB) | SSIM | sampling (s) |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(f"| {r.model} | {r.spikes} | {r.negative_spikes} | {r.mse:.2f} | "
                     f"{r.psnr:.2f} | {r.ssim:.3f} | {r.seconds:.2f} |")
    return "\n".join(lines) + "\n"


def metrics_csv(rows: list[DemoRow]) -> str:
    """The demo's metrics as CSV."""
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(["model", "spikes", "negative_spikes", "mse", "psnr", "ssim", "seconds"])
    for r in rows:
        writer.writerow([r.model, r.spikes, r.negative_spikes, f"{r.mse:.4f}", f"{r.psnr:.4f}",
                         f"{r.ssim:.5f}", f"{r.seconds:.3f}"])
    return buf.getvalue()


def run_rtl_demo(
    scene_arg: str,
    out_dir: Path,
    size: tuple[int, int] = DEMO_RTL_SIZE,
    steps: int = DEMO_RTL_STEPS,
    sim: str = "verilator",
    lanes: int = DEMO_RTL_LANES,
) -> dict:
    """Generate the default design point's streaming-array Verilog and verify it.

    Writes ``out_dir/point.toml``, the Verilog of ``RvsmStreamArray(contract, lanes)`` and
    its port map, then runs ``steps`` steps of ``scene_arg`` (rendered at ``size``) on
    ``sim`` through cocotb, spike for spike against the fixed twin. Returns the
    verification result (``compared``, ``mismatches``, ``first_mismatch``, ``waves``,
    timings) plus ``verilog`` and ``generate_seconds``.
    """
    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.point_toml import save_design_point
    from rvsm.rtl.architectures.verilog import write_outputs
    from rvsm.sim.cosim.verify import verify

    point = default_design_point().with_size(*size)
    point_path = out_dir / "point.toml"
    save_design_point(point_path, point)
    paths, generated = write_outputs(point.contract(), out_dir, "stream", lanes=lanes)
    result = verify(scene_arg, point_path, sim=sim, steps=steps, work_dir=out_dir / "verify",
                    arch="stream", lanes=lanes)
    result.update(verilog=str(paths["verilog"]), generate_seconds=generated.seconds)
    return result
