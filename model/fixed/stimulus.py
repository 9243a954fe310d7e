"""RTL stimulus: exactly what the fixed twin saw, and what it answered (SPEC section 5).

A stimulus file (``.npz``, no pickles) holds:

- ``codes``: ``(T, H, W) uint16`` ADC codes, the per-step input of the array;
- ``thresholds``: ``(S, H, W) int64`` integer thresholds (accumulator LSBs);
- ``spikes``: ``(T, S, H, W) int8`` expected spikes in {-1, 0, 1};
- ``weights``: ``(S, 2Lmax+1, 2Lmax+1) int64`` integer kernels, each centred and
  zero-padded to the largest template; ``half_widths``: ``(S,) int64`` their ``L``;
- ``contract``: JSON of the :class:`~.core.ArrayContract` fields (weights as nested
  lists); ``point``: the design point's TOML text; ``meta``: JSON metadata.

A testbench loads it with :func:`load_stimulus`, configures the RTL from ``contract`` and
``thresholds``, drives ``codes`` step by step and compares every spike.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import RvsmError
from ..scene import Scene
from .config import DesignPoint, design_point_toml, parse_design_point
from .core import ArrayContract
from .twin import simulate_fixed

STIMULUS_KEYS = (
    "codes", "thresholds", "spikes", "weights", "half_widths", "contract", "point", "meta",
)


@dataclass
class Stimulus:
    """Per-step ADC ``codes (T, H, W) uint16``, ``thresholds (S, H, W) int64``, expected
    ``spikes (T, S, H, W) int8``, the integer ``contract`` and (when known) its point."""

    codes: np.ndarray
    thresholds: np.ndarray
    spikes: np.ndarray
    contract: ArrayContract
    point: DesignPoint | None = None
    meta: dict = field(default_factory=dict)

    def check(self) -> bool:
        """True when ``contract.run(codes, thresholds)`` reproduces ``spikes`` exactly."""
        return bool(np.array_equal(self.contract.run(self.codes, self.thresholds), self.spikes))


def make_stimulus(
    scene: Scene, point: DesignPoint, progress: bool = False, num_steps: int | None = None
) -> Stimulus:
    """Run the fixed twin on ``scene`` and keep its inputs and outputs.

    ``num_steps`` keeps only the first steps of the scene (a shorter testbench run).
    """
    if num_steps is not None:
        if isinstance(num_steps, bool) or int(num_steps) < 1:
            raise RvsmError(f"number of steps must be an integer >= 1, got {num_steps!r}")
        if num_steps < scene.num_steps:
            scene = _first_steps(scene, int(num_steps))
    run = simulate_fixed(scene, point, progress=progress, keep_codes=True)
    assert run.codes is not None
    meta = dict(run.meta, kind="stimulus")
    return Stimulus(run.codes, run.thresholds, run.spikes, run.contract, run.point, meta)


def _first_steps(scene: Scene, steps: int) -> Scene:
    """A scene whose steps are the first ``steps`` of ``scene`` (same brightness)."""
    m = scene.steps_per_frame
    if scene.hold:
        frames = scene.frames[: -(-steps // m)]
        out = Scene(scene.name, frames, m, True)
    else:
        frames = scene.frames[: -(-steps // m) + 1]
        out = Scene(scene.name, frames, m, False)
    if out.num_steps == steps:
        return out
    return Scene(scene.name, out.brightness(0, steps), 1, True)


def save_stimulus(path: str | os.PathLike, stim: Stimulus) -> None:
    """Write ``stim`` as ``.npz`` (keys in the module docstring), atomically."""
    c = stim.contract
    if c.adc_bits > 16:
        raise RvsmError(f"stimulus files hold 16-bit codes; adc.bits = {c.adc_bits} > 16")
    big = max(len(k) for k in c.weights)
    weights = np.zeros((c.num_scales, big, big), dtype=np.int64)
    for s, k in enumerate(c.weight_arrays):
        off = (big - k.shape[0]) // 2
        weights[s, off:off + k.shape[0], off:off + k.shape[0]] = k
    arrays = {
        "codes": np.asarray(stim.codes, dtype=np.uint16),
        "thresholds": np.asarray(stim.thresholds, dtype=np.int64),
        "spikes": np.asarray(stim.spikes, dtype=np.int8),
        "weights": weights,
        "half_widths": np.array([len(k) // 2 for k in c.weights], dtype=np.int64),
        "contract": np.array(json.dumps(asdict(c))),
        "point": np.array(design_point_toml(stim.point) if stim.point else ""),
        "meta": np.array(json.dumps(stim.meta, sort_keys=True)),
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)


def load_stimulus(path: str | os.PathLike) -> Stimulus:
    """Read a stimulus file written by :func:`save_stimulus`."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"stimulus file {p} does not exist")
    try:
        with np.load(p, allow_pickle=False) as data:
            missing = set(STIMULUS_KEYS) - set(data.files)
            if missing:
                raise RvsmError(
                    f"{p} is not an rvsm stimulus file: missing {', '.join(sorted(missing))}"
                )
            arrays = {k: data[k] for k in STIMULUS_KEYS}
    except RvsmError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise RvsmError(f"{p} is not a readable stimulus file: {exc}") from None
    raw = json.loads(str(arrays["contract"]))
    raw["weights"] = tuple(tuple(tuple(int(v) for v in row) for row in k) for k in raw["weights"])
    contract = ArrayContract(**raw)
    point_text = str(arrays["point"])
    point = parse_design_point(point_text, str(p)) if point_text else None
    return Stimulus(
        codes=arrays["codes"],
        thresholds=arrays["thresholds"].astype(np.int64),
        spikes=arrays["spikes"].astype(np.int8),
        contract=contract,
        point=point,
        meta=json.loads(str(arrays["meta"])),
    )
