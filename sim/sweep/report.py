"""Sweep reports: per-design aggregates, Pareto front, figures and a markdown report.

A *design* is one combination of axis values; its rows are its scenes x noise x seeds.
Its PSNR cost is the worst deviation from the float model, ``max |psnr_float -
psnr_fixed|`` over those rows, in dB (a fixed point that beats the float model by 1 dB
does not model it either);
its hardware cost is measured on the streaming array (``rvsm.rtl.fpga.lane_cost``):
logic per lane (ECP5 LUT4 from yosys, the slope between the sweep's ``[hardware] lanes``
at ``[hardware] size``; without synthesis, the proxy ``adc.bits + weights.bits +
datapath.accumulator_bits`` bits), flip-flops per lane, optionally Fmax, and the exact
state memory of the design point at its own (sensor) size: accumulators, thresholds and
line buffers. The Pareto fronts put the PSNR cost against logic per lane and against
memory bits. Figures are returned as matplotlib Figures; only :func:`write_report`
writes files.
"""

from __future__ import annotations

import os
import sys
from collections import defaultdict
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rvsm.model.fixed.design_point import FIELD_BY_PATH, FIELD_PATH
from rvsm.model.fixed.point_toml import parse_design_point
from rvsm.model.infra.atomic import atomic_path, write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.camera import state_memory
from rvsm.sim.sweep.fit import FitConstraint, assess_design, fit_markdown, parse_constraint
from rvsm.sim.sweep.store import open_existing

PROXY_LABEL = "adc + weight + accumulator bits (proxy: no synthesis)"
LOGIC_LABEL = "logic per lane (ECP5 LUT4, yosys)"
MEMORY_LABEL = "state memory of the sensor (Mbit)"


@dataclass
class DesignSummary:
    """Aggregate of one design over its rows (costs in dB, logic per lane, memory bits)."""

    design_id: str
    axes: dict[str, Any]
    values: dict[str, Any]
    toml: str
    model: str
    rows: list[dict[str, Any]]
    worst_cost: float
    worst_signed: float
    mean_cost: float
    worst_ssim_cost: float
    min_agreement: float
    max_saturation: float
    lut4_per_lane: float | None
    ff_per_lane: float | None
    fmax_mhz: float | None
    memory_bits: int
    proxy_bits: int
    complete: bool = True
    #: device -> :class:`~rvsm.rtl.fpga.feasibility.Feasibility` under the sweep's
    #: constraint (:mod:`rvsm.sim.sweep.fit`); empty without one.
    feasibility: dict[str, Any] = field(default_factory=dict)

    @property
    def hw(self) -> float:
        """Logic cost used for the Pareto front (LUT4 per lane, else the bit proxy)."""
        return self.lut4_per_lane if self.lut4_per_lane is not None else self.proxy_bits

    @property
    def label(self) -> str:
        """Swept fields with their resolved values, e.g. ``adc.bits=6, weights.bits=9``."""
        return ", ".join(f"{k}={v}" for k, v in self.values.items())


def summarise(rows: list[dict[str, Any]]) -> list[DesignSummary]:
    """Group ``ok`` result rows by design; ``complete`` marks designs with every
    (scene, noise, seed, steps, size) seen for any design."""
    by: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        if r["status"] == "ok":
            by[r["design_id"]].append(r)
    runs = {(r["scene"], r["noise"], r["seed"], r["steps"], r["size"])
            for rs in by.values() for r in rs}
    out = []
    for did, rs in by.items():
        point = parse_design_point(rs[0]["design_toml"], f"design {did}")
        values = {p: _value(point, p) for p in rs[0]["axes"]}
        costs = np.array([r["psnr_cost"] for r in rs], dtype=float)
        have = {(r["scene"], r["noise"], r["seed"], r["steps"], r["size"]) for r in rs}
        logic = rs[0].get("lut4_per_lane")
        ffs, fmax = rs[0].get("ff_per_lane"), rs[0].get("fmax_mhz")
        out.append(DesignSummary(
            design_id=did, axes=rs[0]["axes"], values=values, toml=rs[0]["design_toml"],
            model=point.model, rows=rs, worst_cost=float(np.abs(costs).max()),
            worst_signed=float(costs.max()),
            mean_cost=float(costs.mean()),
            worst_ssim_cost=float(max(r["ssim_cost"] for r in rs)),
            min_agreement=float(min(r["agreement"] for r in rs)),
            max_saturation=float(max(r["max_saturation_rate"] for r in rs)),
            lut4_per_lane=None if logic is None else float(logic),
            ff_per_lane=None if ffs is None else float(ffs),
            fmax_mhz=None if fmax is None else float(fmax),
            memory_bits=state_memory(point.contract()).total,
            proxy_bits=point.adc_bits + point.weight_bits + point.accumulator_bits,
            complete=have >= runs,
        ))
    if any(d.lut4_per_lane is None for d in out):  # mixed: compare like with like
        for d in out:
            d.lut4_per_lane = None
    return sorted(out, key=lambda d: (d.hw, d.worst_cost))


def _value(point, path: str) -> Any:
    v = getattr(point, FIELD_BY_PATH[path].name)
    return list(v) if isinstance(v, tuple) else v


def pareto_mask(hw: list[float] | np.ndarray, cost: list[float] | np.ndarray) -> np.ndarray:
    """True where a point is not dominated, minimising both ``hw`` and ``cost``: j
    dominates i when ``hw[j] <= hw[i]``, ``cost[j] <= cost[i]`` and one is strict."""
    x, y = np.asarray(hw, dtype=float), np.asarray(cost, dtype=float)
    keep = np.ones(x.size, dtype=bool)
    for i in range(x.size):
        dom = (x <= x[i]) & (y <= y[i]) & ((x < x[i]) | (y < y[i]))
        keep[i] = not dom.any()
    return keep


def recommend(designs: list[DesignSummary], tolerance: float = 0.1) -> DesignSummary | None:
    """The smallest complete design (hardware cost, then PSNR cost) whose PSNR stays within
    ``tolerance`` dB of the float model on every run (``worst_cost`` is ``max |cost|``)."""
    ok = [d for d in designs if d.complete and d.worst_cost <= tolerance]
    return min(ok, key=lambda d: (d.hw, d.worst_cost), default=None)


def width_cost_figure(designs: list[DesignSummary], tolerance: float = 0.1):
    """PSNR cost against each swept numeric field: every design (grey dots, worst cost
    over scenes and noise) and, per model (scale ladder), the best worst-case cost
    reachable at each width (line). Returns a matplotlib Figure."""
    from matplotlib.figure import Figure

    paths = [p for p in (designs[0].values if designs else {})
             if all(isinstance(d.values.get(p), (int, float)) and
                    not isinstance(d.values.get(p), bool) for d in designs)]
    n = max(1, len(paths))
    fig = Figure(figsize=(4.2 * n, 3.6))
    axs = fig.subplots(1, n, squeeze=False)
    for ax, path in zip(axs[0], paths, strict=False):
        xs = [d.values[path] for d in designs]
        ax.scatter(xs, [d.worst_cost for d in designs], s=12, color="0.75", zorder=1,
                   label="design (worst scene)")
        for model in sorted({d.model for d in designs}):
            best: dict[float, float] = {}
            for d in designs:
                if d.model == model:
                    x = d.values[path]
                    best[x] = min(best.get(x, np.inf), d.worst_cost)
            ks = sorted(best)
            ax.plot(ks, [best[k] for k in ks], marker="o", zorder=2, label=f"{model} best")
        ax.axhline(tolerance, color="tab:red", lw=0.8, ls="--", label=f"{tolerance} dB")
        if min(d.worst_cost for d in designs) > 0:
            ax.set_yscale("log")
        ax.set_xlabel(path)
        ax.set_ylabel("max |PSNR float - fixed| (dB)")
        ax.grid(alpha=0.3)
    if not paths:
        axs[0][0].text(0.5, 0.5, "no numeric axes", ha="center", va="center")
    axs[0][0].legend(fontsize=7)
    fig.suptitle("PSNR deviation from float against each width (worst over scenes, noise)")
    fig.tight_layout()
    return fig


def pareto_figure(designs: list[DesignSummary], tolerance: float = 0.1):
    """Worst PSNR cost against logic per lane (left) and against the sensor's state memory
    (right); each panel's Pareto front in colour, dominated points grey. Returns a
    matplotlib Figure."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.0, 4.4))
    axs = fig.subplots(1, 2)
    cost = np.array([d.worst_cost for d in designs], dtype=float)
    uses_logic = bool(designs) and designs[0].lut4_per_lane is not None
    panels = ((axs[0], [d.hw for d in designs], LOGIC_LABEL if uses_logic else PROXY_LABEL),
              (axs[1], [d.memory_bits / 1e6 for d in designs], MEMORY_LABEL))
    for k, (ax, xs, label) in enumerate(panels):
        hw = np.array(xs, dtype=float)
        mask = pareto_mask(hw, cost) if designs else np.zeros(0, bool)
        ax.scatter(hw[~mask], cost[~mask], s=14, color="0.7", label="dominated")  # grey
        order = np.argsort(hw[mask])
        ax.plot(hw[mask][order], cost[mask][order], "o-", color="tab:blue",
                drawstyle="steps-post", label="Pareto front")
        # numbered as in the report's Pareto tables: by this panel's cost axis, then PSNR
        front = sorted((i for i, m in enumerate(mask) if m), key=lambda i: (hw[i], cost[i]))
        for n, i in enumerate(front, 1):
            ax.annotate(f"{'PM'[k]}{n}", (hw[i], max(cost[i], 1e-3)), fontsize=7,
                        xytext=(3, 3), textcoords="offset points")
        ax.axhline(tolerance, color="tab:red", lw=0.8, ls="--", label=f"{tolerance} dB")
        ax.set_xlabel(label)
        if designs and cost.min() > 0:
            ax.set_yscale("log")
        ax.set_ylabel("max |PSNR float - fixed| (dB)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def report_markdown(db_name: str, designs: list[DesignSummary], invalid: list[dict],
                    errors: list[dict], sweeps: list[tuple[str, str]], tolerance: float,
                    figures: dict[str, str], constraint: FitConstraint | None = None) -> str:
    """The markdown report (``figures``: caption -> relative file name; ``constraint``:
    a section ranking the designs that fit, :func:`~rvsm.sim.sweep.fit.fit_markdown`)."""
    rec = recommend(designs, tolerance)
    hw_sizes = sorted({f"{r.get('hw_size')} at lanes {r.get('hw_lanes')}"
                       if r.get("hw_size") else "-" for d in designs for r in d.rows[:1]})
    runs = sorted({(r["scene"], r["noise"], r["seed"], r["size"], r["steps"])
                   for d in designs for r in d.rows})
    lines = [
        f"# Design sweep report: {db_name}", "",
        f"Sweeps: {', '.join(f'`{p}` ({h})' for h, p in sweeps) or '-'}. "
        f"{len(designs)} valid design(s), {len(invalid)} invalid, {len(errors)} failed row(s); "
        f"{len(runs)} run(s) per design (scene x noise x seed): "
        f"{', '.join(sorted({r[0] for r in runs}))}; "
        f"sizes {', '.join(sorted({r[3] for r in runs}))}, "
        f"steps {', '.join(str(s) for s in sorted({r[4] for r in runs}))}.",
        "",
        f"PSNR cost = PSNR(float) - PSNR(fixed) in dB; `worst |cost|` is the largest "
        "deviation over a design's runs (used for the recommendation and the Pareto front), "
        "`worst cost` the largest signed cost. Hardware cost is measured on the streaming "
        "array: logic per lane = ECP5 LUT4 (LUT4 + 2 CCU2C) per extra lane from yosys "
        f"`synth_ecp5`, synthesised at {', '.join(hw_sizes)} (the slope; the I/O harness "
        "removed), and the exact state memory of the sensor at the design point "
        "(accumulators + thresholds + line buffers); see docs/fpga.md.", "",
    ]
    for cap, f in figures.items():
        lines += [f"![{cap}]({f})", ""]
    if constraint is not None:
        lines += fit_markdown(designs, constraint)
    lines += [f"## Recommended (smallest within {tolerance} dB on every run)", ""]
    if rec is None:
        lines += ["No complete design stays within the bound.", ""]
    else:
        lines += [f"**{rec.label}**: {_hw_text(rec)}, worst PSNR cost "
                  f"{rec.worst_cost:.3f} dB.", "", "```toml", rec.toml.rstrip(), "```", "",
                  "| scene | noise | PSNR float | PSNR fixed | PSNR cost | SSIM cost | MSE cost "
                  "| agreement | max saturation |", "|---|---|---|---|---|---|---|---|---|"]
        for r in sorted(rec.rows, key=lambda r: (r["scene"], r["noise"], r["seed"])):
            lines.append(
                f"| {r['scene']} | {'on' if r['noise'] else 'off'} | {r['psnr_float']:.3f} | "
                f"{r['psnr_fixed']:.3f} | {r['psnr_cost']:+.3f} | {r['ssim_cost']:+.4f} | "
                f"{r['mse_cost']:+.2f} | {100 * r['agreement']:.1f} % | "
                f"{100 * r['max_saturation_rate']:.3f} % |")
        lines.append("")
    costs = [d.worst_cost for d in designs]
    front = [d for d, m in zip(designs, pareto_mask([d.hw for d in designs], costs),
                               strict=True) if m]
    by_memory = sorted(designs, key=lambda d: (d.memory_bits, d.worst_cost))
    mem_front = [d for d, m in zip(
        by_memory, pareto_mask([d.memory_bits for d in by_memory],
                               [d.worst_cost for d in by_memory]), strict=True) if m]
    lines += ["## Pareto points: PSNR cost against logic per lane", "", _table(front), ""]
    for i, d in enumerate(front, 1):
        lines += [f"### P{i}: {d.label}", "", "```toml", d.toml.rstrip(), "```", ""]
    lines += ["## Pareto points: PSNR cost against state memory", "",
              _table(mem_front, "M"), ""]
    lines += ["## All designs", "", _table(designs), ""]
    if invalid:
        lines += ["## Invalid designs (refused by design point validation)", "",
                  "| axes | reason |", "|---|---|"]
        seen = set()
        for r in invalid:
            if r["design_id"] not in seen:
                seen.add(r["design_id"])
                axes = ", ".join(f"{k}={v}" for k, v in r["axes"].items())
                lines.append(f"| {axes} | {r['error']} |")
        lines.append("")
    if errors:
        lines += ["## Failed rows (rerun the sweep to retry)", ""]
        lines += [f"- {r['design_id']} {r['scene']}: {r['error']}" for r in errors[:50]]
        lines.append("")
    return "\n".join(lines)


def _hw_text(d: DesignSummary) -> str:
    memory = f"{d.memory_bits / 1e6:.2f} Mbit of state"
    if d.lut4_per_lane is None:
        return f"{d.proxy_bits} bits (proxy), {memory}"
    fmax = "" if d.fmax_mhz is None else f", Fmax {d.fmax_mhz:.1f} MHz"
    return (f"{d.lut4_per_lane:.0f} LUT4 and {d.ff_per_lane:.0f} flip-flops per lane"
            f"{fmax}, {memory}")


def _table(designs: list[DesignSummary], prefix: str = "") -> str:
    head = ("| design | LUT4/lane | FF/lane | Fmax | memory | worst \\|cost\\| | worst cost | "
            "mean cost | worst SSIM cost | min agreement | max saturation | complete |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|")
    rows = [
        f"| {f'{prefix}{i}: ' if prefix else ''}{d.label} | {_fmt(d.lut4_per_lane, '.0f')} | "
        f"{_fmt(d.ff_per_lane, '.0f')} | {_fmt(d.fmax_mhz, '.1f')} | "
        f"{d.memory_bits / 1e6:.2f} Mbit | "
        f"{d.worst_cost:.3f} dB | {d.worst_signed:+.3f} | {d.mean_cost:+.3f} | "
        f"{d.worst_ssim_cost:+.4f} | "
        f"{100 * d.min_agreement:.1f} % | {100 * d.max_saturation:.3f} % | "
        f"{'yes' if d.complete else 'no'} |" for i, d in enumerate(designs, 1)]
    return "\n".join([head, *rows])


def _fmt(v: float | None, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def stored_constraint(texts: list[tuple[str, str]]) -> FitConstraint | None:
    """The device constraint of the most recently run sweep file that has one
    (``texts``: ``(path, text)`` in the order run), or None."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    for path, text in reversed(texts):
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError:  # pragma: no cover - stored only after parsing
            continue
        found = parse_constraint(data, path)
        if found is not None:
            return found
    return None


def write_report(db: str | os.PathLike | Any, out_dir: str | os.PathLike,
                 tolerance: float = 0.1, constraint: FitConstraint | None = None
                 ) -> tuple[list[Path], dict[str, Any] | None]:
    """Write ``report.md``, ``width-cost.png`` and ``pareto.png`` into ``out_dir``.

    ``db``: a database's path or an open one (:func:`rvsm.sim.sweep.shipped.open_results`).
    ``constraint``: the devices and camera to check every design against (default: the
    one of the most recent sweep file in the database that states one, if any).
    Returns the files written and the recommended design (``label``, ``toml``,
    ``worst_cost``, ``lut4_per_lane``, ``ff_per_lane``, ``memory_bits``; with a
    constraint also per device ``fits``: the feasible designs ranked by PSNR cost ``{label,
    worst_cost, summary}``, ``infeasible``: ``{label, summary}``, ``verdicts``) or None.
    """
    with nullcontext(db) if hasattr(db, "results") else open_existing(db) as store:
        rows, sweeps, texts = store.results(), store.sweeps(), store.sweep_texts()
    designs = summarise(rows)
    if not designs:
        raise RvsmError(f"{store.path}: no finished results yet; run the sweep first")
    if constraint is None:
        constraint = stored_constraint(texts)
    if constraint is not None:
        for d in designs:
            d.feasibility = assess_design(d.toml, d.rows[0], constraint)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figs = {"PSNR cost against each width": ("width-cost.png", width_cost_figure),
            "Pareto fronts: PSNR cost against logic per lane and against state memory":
                ("pareto.png", pareto_figure)}
    files = []
    for _cap, (name, make) in figs.items():
        fig = make(designs, tolerance)
        with atomic_path(out / name) as tmp:
            fig.savefig(tmp, dpi=130)
        files.append(out / name)
    text = report_markdown(
        store.path.name, designs, [r for r in rows if r["status"] == "invalid"],
        [r for r in rows if r["status"] == "error"], sweeps, tolerance,
        {cap: name for cap, (name, _) in figs.items()}, constraint)
    write_text_atomic(out / "report.md", text)
    files.append(out / "report.md")
    rec = recommend(designs, tolerance)
    info = None if rec is None else {"label": rec.label, "toml": rec.toml,
                                      "worst_cost": rec.worst_cost,
                                      "lut4_per_lane": rec.lut4_per_lane,
                                      "ff_per_lane": rec.ff_per_lane,
                                      "memory_bits": rec.memory_bits}
    if constraint is not None:
        info = dict(info or {})
        info["fits"] = {name: [{"label": d.label, "worst_cost": d.worst_cost,
                                "summary": d.feasibility[name].summary()}
                               for d in sorted(designs, key=lambda d: (d.worst_cost, d.label))
                               if d.feasibility[name].feasible]
                        for name in constraint.devices}
        info["infeasible"] = {name: [{"label": d.label,
                                      "summary": d.feasibility[name].summary()}
                                     for d in designs if not d.feasibility[name].feasible]
                              for name in constraint.devices}
        info["verdicts"] = {name: [{"label": d.label, **d.feasibility[name].to_dict()}
                                   for d in designs] for name in constraint.devices}
    return files, info


__all__ = ["FIELD_PATH", "DesignSummary", "pareto_figure", "pareto_mask", "recommend",
           "report_markdown", "stored_constraint", "summarise", "width_cost_figure",
           "write_report"]
