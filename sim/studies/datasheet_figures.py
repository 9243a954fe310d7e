"""The pictures of ``rvsm datasheet`` (matplotlib, Agg): resources against the device, the
clock the camera needs against Fmax, the image-quality costs per scene and the
reconstructions side by side. Each returns a figure; the caller saves it atomically.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rvsm.sim.studies.point_quality import PointQuality

__all__ = ["clock_figure", "costs_figure", "reconstruction_figure", "resources_figure"]

#: Panel titles of the reconstruction picture, in order.
PANELS = (("truth", "ground truth"), ("default_float", "float dog4 (default)"),
          ("float", "own float"), ("twin", "fixed twin"))


def _figure(width: float, height: float):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.figure(figsize=(width, height), dpi=100)


def resources_figure(rows: Sequence[tuple[str, float | None, float | None]], device: str):
    """Bars of percent of ``device`` per resource: ``rows`` of ``(resource, measured %,
    estimated %)`` (None: no figure)."""
    fig = _figure(6.0, 3.0)
    ax = fig.add_subplot(1, 1, 1)
    x = np.arange(len(rows))
    for i, (label, offset) in enumerate((("measured (nextpnr)", -0.2),
                                         ("estimate (feasibility model)", 0.2))):
        values = [r[1 + i] for r in rows]
        xs = [xi + offset for xi, v in zip(x, values, strict=True) if v is not None]
        ys = [v for v in values if v is not None]
        if ys:
            ax.bar(xs, ys, width=0.4, label=label)
    ax.axhline(100.0, color="k", lw=0.8)
    ax.set_xticks(x, [r[0] for r in rows])
    ax.set_ylabel(f"% of {device}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def clock_figure(lanes: Sequence[int], clock_mhz: Sequence[float], fmax_mhz: float | None,
                 chosen: int, fmax_label: str):
    """Clock needed (MHz) against lanes (log-log), the Fmax line and the chosen lanes."""
    fig = _figure(6.0, 3.2)
    ax = fig.add_subplot(1, 1, 1)
    ax.loglog(lanes, clock_mhz, "o-", ms=3, label="clock needed H*W/P*rate")
    if fmax_mhz is not None:
        ax.axhline(fmax_mhz, color="r", lw=1, label=fmax_label)
    ax.axvline(chosen, color="g", lw=1, ls="--", label=f"P = {chosen}")
    ax.set_xlabel("lanes P (pixels per clock)")
    ax.set_ylabel("MHz")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def costs_figure(quality: PointQuality):
    """Per scene, the twin's PSNR against its own float model and against the default
    dog4 float model (dB, twin - float: above 0 the chip is better), noise off and on."""
    settings = [n for n in (False, True) if quality.rows_with(n)]
    fig = _figure(6.5, 2.8 * len(settings))
    for k, noise in enumerate(settings):
        rows = quality.rows_with(noise)
        ax = fig.add_subplot(len(settings), 1, k + 1)
        x = np.arange(len(rows))
        ax.bar(x - 0.2, [-r.quantisation_cost_db for r in rows], width=0.4,
               label="twin - own float (the fixed point)")
        ax.bar(x + 0.2, [-r.chip_cost_db for r in rows], width=0.4,
               label="twin - dog4 float (the chip against the default)")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(x, [r.scene for r in rows])
        ax.set_ylabel("dB (above 0: twin better)")
        ax.set_title(f"noise {'on' if noise else 'off'}", fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def reconstruction_figure(images: Mapping[str, np.ndarray], title: str):
    """The four images of :func:`~rvsm.sim.studies.point_quality.reconstructions` side by
    side, grey, 0..255."""
    h, w = next(iter(images.values())).shape
    fig = _figure(3.0 * len(PANELS), 3.0 * h / w + 0.6)
    for i, (key, label) in enumerate(PANELS):
        ax = fig.add_subplot(1, len(PANELS), i + 1)
        ax.imshow(images[key], cmap="gray", vmin=0, vmax=255, interpolation="nearest")
        ax.set_title(label, fontsize=9)
        ax.axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig
