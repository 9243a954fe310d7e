"""Quantisation reports in the spirit of hls4ml's profiling (``hls4ml.model.profiling``).

Per scale: how often accumulators saturated, the observed range of per-step sums and of
accumulators against the representable range, and the weights' quantisation error.
:func:`profile_figure` draws hls4ml's ``numerical`` plot: one horizontal box per quantity
on a log2 axis of ``|value|`` with a grey band showing what its format can represent.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.results import FixedRun
from rvsm.model.fixed.weights import weight_error_report
from rvsm.model.fixed.widths import signed_range
from rvsm.model.infra.errors import RvsmError


def profile_report(run: FixedRun) -> dict:
    """A JSON-ready report of ``run`` (needs the stats every :class:`FixedRun` has).

    ``scales`` is a list with, per scale: ``saturated`` (accumulator-steps) and
    ``saturated_fraction``; ``sum_min``/``sum_max`` (before the shift) with the
    representable ``sum_range``; ``shifted_min``/``shifted_max``; ``acc_min``/``acc_max``
    (before saturation) with ``acc_range``; ``acc_headroom_bits`` (spare bits above the
    largest ``|acc|``, negative when it saturated); ``threshold`` (nominal, LSBs); and
    ``weights`` (the :func:`weight_error_report` entry).
    """
    p, st, c = run.point, run.stats, run.contract
    lo, hi = signed_range(p.accumulator_bits)
    werr = weight_error_report(p.model, p.weight_bits, p.weight_frac_bits, p.weight_rounding)
    scales = []
    for s in range(p.num_scales):
        peak = max(abs(int(st.acc_min[s])), abs(int(st.acc_max[s])), 1)
        scales.append({
            "scale": s,
            "saturated": int(st.saturated[s]),
            "saturated_fraction": float(st.saturated[s]) / max(st.steps * st.accumulators, 1),
            "sum_min": int(st.sum_min[s]),
            "sum_max": int(st.sum_max[s]),
            "sum_range": list(c.sum_range(s)),
            "shifted_min": int(st.shifted_min[s]),
            "shifted_max": int(st.shifted_max[s]),
            "acc_min": int(st.acc_min[s]),
            "acc_max": int(st.acc_max[s]),
            "acc_range": [lo, hi],
            "acc_headroom_bits": (p.accumulator_bits - 1) - peak.bit_length(),
            "threshold": int(p.nominal_thresholds()[s]),
            "weights": werr[s],
        })
    return {
        "scene": run.meta.get("scene"),
        "model": p.model,
        "steps": st.steps,
        "accumulators_per_scale": st.accumulators,
        "design_point": p.to_dict(),
        "scales": scales,
    }


def format_profile(report: dict) -> str:
    """The report as an aligned text table (what ``rvsm profile`` prints)."""
    dp = report["design_point"]
    lines = [
        f"fixed-point profile: {report['model']} on {report['scene']}, {report['steps']} steps, "
        f"{report['accumulators_per_scale']} accumulators/scale",
        f"ADC {dp['adc_bits']} b ({dp['adc_rounding']}), weights {dp['weight_bits']}/"
        f"{dp['weight_frac_bits']} ({dp['weight_rounding']}), shift {dp['shift']}, "
        f"accumulator {dp['accumulator_bits']} b signed saturating",
        "",
        f"{'scale':>5} {'saturated':>10} {'sat %':>8} {'sum min..max':>25} "
        f"{'representable sum':>25} {'acc min..max':>25} {'headroom':>8} {'threshold':>10}",
    ]
    for r in report["scales"]:
        lines.append(
            f"{r['scale']:>5} {r['saturated']:>10} {100 * r['saturated_fraction']:>7.3f}% "
            f"{_span(r['sum_min'], r['sum_max']):>25} {_span(*r['sum_range']):>25} "
            f"{_span(r['acc_min'], r['acc_max']):>25} {r['acc_headroom_bits']:>6} b "
            f"{r['threshold']:>10}"
        )
    lines += [
        "",
        f"{'scale':>5} {'weights int':>14} {'range':>16} {'max |err|':>11} {'max err/LSB':>11} "
        f"{'rms err':>10} {'zeroed':>6} {'sum float':>10} {'sum fixed':>10}",
    ]
    for r in report["scales"]:
        w = r["weights"]
        lines.append(
            f"{r['scale']:>5} {_span(w['int_min'], w['int_max']):>14} "
            f"{_span(w['range_min'], w['range_max']):>16} {w['max_abs_error']:>11.3e} "
            f"{w['max_abs_error_lsb']:>11.3f} {w['rms_error']:>10.3e} {w['zero_taps']:>6} "
            f"{w['sum_float']:>10.6f} {w['sum_fixed']:>10.6f}"
        )
    return "\n".join(lines)


def _span(lo: int, hi: int) -> str:
    return f"{lo}..{hi}"


def profile_figure(run: FixedRun):
    """hls4ml ``numerical``-style plot; returns a :class:`matplotlib.figure.Figure`.

    Left: per scale, ``|w|`` of the float weights (box 25..75 %, whiskers min..max) in
    weight units, grey band ``[2**-frac, 2**(bits-1-frac)]``. Right: per scale, the
    distribution of ``|sum|`` and ``|acc|`` bit lengths (in LSBs), grey bands their
    representable ranges, a red tick at the threshold. Needs ``histograms=True`` in
    :func:`~.twin.simulate_fixed` for the right panel's boxes (min..max otherwise).
    """
    from matplotlib.figure import Figure

    p, st, c = run.point, run.stats, run.contract
    if st.steps == 0:
        raise RvsmError("cannot profile an empty run (0 steps)")
    fig = Figure(figsize=(11, 1.2 + 0.9 * p.num_scales * 2), layout="constrained")
    ax_w, ax_a = fig.subplots(1, 2)
    # Left: weights.
    kernels = p.spec.kernels()
    ax_w.axvspan(-p.weight_frac_bits, p.weight_bits - 1 - p.weight_frac_bits,
                 color="0.85", zorder=0, label="representable")
    for i, k in enumerate(kernels):
        lg = np.log2(np.abs(k[k != 0]))
        q = np.percentile(lg, [0, 25, 50, 75, 100])
        _draw_box(ax_w, i, q[1], q[2], q[3], q[0], q[4])
    ax_w.set_yticks(np.arange(len(kernels)), [f"scale {s} weights" for s in range(len(kernels))])
    ax_w.set_ylim(-0.7, len(kernels) - 0.3)
    ax_w.set_xlabel("log2 |weight|")
    ax_w.set_title(f"weights: {p.weight_bits} bits, {p.weight_frac_bits} fraction")
    ax_w.legend(loc="lower right", fontsize="small")
    # Right: sums and accumulators, in integer LSBs.
    rows = []
    lo, hi = signed_range(p.accumulator_bits)
    for s in range(p.num_scales):
        s_lo, s_hi = c.sum_range(s)
        rows.append((f"scale {s} sum", st.sum_hist[s] if st.sum_hist is not None else None,
                     (st.sum_min[s], st.sum_max[s]), max(-s_lo, s_hi), None))
        rows.append((f"scale {s} acc", st.acc_hist[s] if st.acc_hist is not None else None,
                     (st.acc_min[s], st.acc_max[s]), hi, p.nominal_thresholds()[s]))
    for i, (_, hist, (vmin, vmax), top, thr) in enumerate(rows):
        ax_a.fill_betweenx([i - 0.4, i + 0.4], 0, np.log2(max(top, 1)), color="0.85", zorder=0)
        peak = max(abs(int(vmin)), abs(int(vmax)), 1)
        if hist is not None and hist.sum() > 0:
            q = _hist_quantiles(hist, (0.25, 0.5, 0.75))
            low = _hist_quantiles(hist, (0.0,))[0]
            _draw_box(ax_a, i, q[0], q[1], q[2], low, np.log2(peak))
        else:
            ax_a.plot([0, np.log2(peak)], [i, i], color="C0")
            ax_a.plot([np.log2(peak)], [i], "|", color="C0", markersize=12)
        if thr is not None:
            ax_a.plot([np.log2(thr)], [i], "|", color="red", markersize=14, mew=2)
    ax_a.set_yticks(np.arange(len(rows)), [r[0] for r in rows])
    ax_a.set_ylim(-0.7, len(rows) - 0.3)
    ax_a.set_xlabel("log2 |value| (LSBs)")
    ax_a.set_title(f"per-step sums and {p.accumulator_bits}-bit accumulators (red: threshold)")
    ax_w.invert_yaxis()
    ax_a.invert_yaxis()
    return fig


def _draw_box(ax, y: float, q1: float, med: float, q3: float, lo: float, hi: float) -> None:
    """A horizontal box (q1..q3, median line) with whiskers lo..hi at height ``y``."""
    from matplotlib.patches import Rectangle

    ax.add_patch(Rectangle((q1, y - 0.3), max(q3 - q1, 0.05), 0.6, fill=False, color="C0"))
    ax.plot([med, med], [y - 0.3, y + 0.3], color="C1")
    ax.plot([lo, q1], [y, y], color="C0")
    ax.plot([q3, hi], [y, y], color="C0")
    ax.plot([lo, hi], [y, y], "|", color="C0", markersize=10)


def _hist_quantiles(hist: np.ndarray, qs: tuple[float, ...]) -> list[float]:
    """Quantiles of ``log2 |v|`` from a bit-length histogram (bin k covers [k-1, k))."""
    cdf = np.cumsum(hist) / hist.sum()
    out = []
    for q in qs:
        k = int(np.searchsorted(cdf, q, side="left")) if q > 0 else int(np.argmax(hist > 0))
        out.append(max(k - 0.5, 0.0))
    return out
