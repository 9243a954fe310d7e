"""Table 1 under several settings in one run: threshold rule x noise preset x decoder.

A *setting* is ``(thresholds, noise_preset, decoder)``: the per-scale threshold rule
(:mod:`rvsm.model.sampling.thresholds`), the noise regime of the ``(N)`` columns
(:mod:`rvsm.model.noise.presets`) and the RVSM decoder (``rvsm`` = the paper's adjoint,
``inverse`` = least squares, :mod:`rvsm.model.decode.inverse`; FSM is always TFI). Work is
shared: each (scene, noise, model, rule) is sampled once and decoded by every decoder;
FSM does not depend on the rule or the decoder and the clean columns do not depend on the
preset, so their runs are shared too. Every model of a scene is scored on the same steps
(:func:`rvsm.model.decode.evaluation.scored_steps` at the nominal ``phi``).
"""

from __future__ import annotations

import csv
import io
import time
from collections.abc import Sequence
from dataclasses import dataclass

from rvsm.model.decode.evaluation import evaluate_spikes, reconstruct_for_display, scored_steps
from rvsm.model.kernels.receptive_fields import model_spec
from rvsm.model.noise.presets import preset_noise
from rvsm.model.sampling.config import DEFAULT_PHI, SamplerConfig
from rvsm.model.sampling.thresholds import rule_thresholds
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.scene import Scene
from rvsm.sim.studies.table import FIG6_CLEAN, FIG6_NOISY, TABLE_MODELS, TableResult

DECODERS = ("rvsm", "inverse")


@dataclass(frozen=True)
class Setting:
    """One table setting: threshold rule, noise preset of the (N) columns, RVSM decoder."""

    thresholds: str = "equal"
    noise_preset: str = "spec"
    decoder: str = "rvsm"

    @property
    def tag(self) -> str:
        """File-name tag, e.g. ``response-paper-inverse``."""
        return f"{self.thresholds}-{self.noise_preset}-{self.decoder}"


def run_settings_table(
    scenes: Sequence[Scene],
    rules: Sequence[str] = ("equal",),
    presets: Sequence[str] = ("spec",),
    decoders: Sequence[str] = ("rvsm",),
    seed: int = 0,
    phi: float = DEFAULT_PHI,
    models: Sequence[str] = TABLE_MODELS,
    progress: bool = False,
) -> dict[Setting, TableResult]:
    """Run the quality table for every setting in ``rules x presets x decoders``.

    Returns one :class:`~rvsm.sim.studies.table.TableResult` per :class:`Setting` (rows also
    carry ``thresholds`` (the per-scale thresholds used), and ``settings`` names the
    setting). Per-scale thresholds of the ``response`` rule are computed on each scene.
    """
    from tqdm.auto import tqdm

    models = [model_spec(m).name for m in models]
    settings = [Setting(r, p, d) for r in rules for p in presets for d in decoders]
    results = {
        s: TableResult(scenes=[sc.name for sc in scenes], models=models,
                       settings={"seed": seed, "phi": phi, "thresholds": s.thresholds,
                                 "noise_preset": s.noise_preset, "decoder": s.decoder,
                                 "noise_k": preset_noise(s.noise_preset).k})
        for s in settings
    }
    shown = set(FIG6_CLEAN) | set(FIG6_NOISY)
    conditions: list[str | None] = [None, *presets]
    runs = len(scenes) * len(conditions) * sum(
        1 if model_spec(m).family == "fsm" else len(rules) for m in models)
    start = time.perf_counter()
    with tqdm(total=runs, desc="rvsm table", unit="run", disable=not progress) as bar:
        for scene in scenes:
            steps = scored_steps(scene, phi)
            show = int(steps[len(steps) // 2])
            for res in results.values():
                res.display_step[scene.name] = show
                res.truth[scene.name] = scene.brightness(show, show + 1)[0]
            thr = {(r, m): rule_thresholds(r, scene, m, phi) for r in rules for m in models
                   if model_spec(m).family != "fsm"}
            for cond in conditions:
                noise = preset_noise(cond, seed) if cond is not None else None
                for model in models:
                    rvsm = model_spec(model).family != "fsm"
                    for rule in (rules if rvsm else rules[:1]):
                        bar.set_postfix_str(f"{scene.name} {cond or 'clean'} {model} {rule}")
                        t0 = time.perf_counter()
                        config = SamplerConfig(model=model, phi=phi, noise=noise,
                                               scale_phi=thr.get((rule, model)))
                        train = sample(scene, config)
                        for dec in (decoders if rvsm else ("auto",)):
                            scores = evaluate_spikes(train.spikes, scene, model, config.phis,
                                                     method=dec, steps=steps)
                            img = None
                            if model in shown:
                                _, img = reconstruct_for_display(
                                    train.spikes, scene, model, config.phis, [show], dec)
                            row = {"scene": scene.name, "noise": cond is not None,
                                   "model": model, **scores,
                                   "thresholds": [float(v) for v in config.phis],
                                   "seconds": time.perf_counter() - t0}
                            for s in settings:
                                if (rvsm and (s.thresholds != rule or s.decoder != dec)) or \
                                        (cond is not None and s.noise_preset != cond):
                                    continue
                                results[s].rows.append(dict(row))
                                if img is not None:
                                    results[s].display[(scene.name, cond is not None,
                                                        model)] = img[0]
                        del train
                        bar.update(1)
    elapsed = time.perf_counter() - start
    for res in results.values():
        res.seconds = elapsed
    return results


def settings_csv(results: dict[Setting, TableResult]) -> str:
    """One CSV over every setting: thresholds rule, noise preset, decoder, then the
    columns of :func:`rvsm.sim.studies.table.table_csv` and the per-scale thresholds."""
    buf = io.StringIO()
    fields = ["rule", "noise_preset", "decoder", "scene", "noise", "model", "method", "mse",
              "psnr", "ssim", "num_scored", "warmup", "phis"]
    writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for s, res in results.items():
        for row in res.rows:
            writer.writerow({
                "rule": s.thresholds, "noise_preset": s.noise_preset, "decoder": s.decoder,
                **{k: row[k] for k in fields[3:-1]},
                "phis": " ".join(f"{v:.4g}" for v in row["thresholds"]),
            })
    return buf.getvalue()
