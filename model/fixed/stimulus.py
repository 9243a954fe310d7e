"""RTL stimulus: exactly what the fixed twin saw, and what it answered (SPEC section 5).

One format from the fixed twin to the RTL: ``rvsm stimulus`` writes it, the cocotb
testbench (:mod:`rvsm.sim.cosim.tb_array`) drives the RTL from it, and
``rvsm verify --stimulus FILE`` replays it. A stimulus file (``.npz``, no pickles) holds:

- ``codes``: ``(T, H, W) uint16`` ADC codes, the per-step input of the array;
- ``thresholds``: ``(S, H, W) int64`` integer thresholds (accumulator LSBs);
- ``spikes``: ``(T, S, H, W) int8`` expected spikes in {-1, 0, 1};
- ``clear_before``: ``(K,) int64`` steps before which the array is cleared (every
  accumulator restarts from 0, thresholds kept; :meth:`ArrayContract.run` semantics);
  empty for one uninterrupted stream. Files without it (older ones) mean empty;
- ``weights``: ``(S, 2Lmax+1, 2Lmax+1) int64`` integer kernels, each centred and
  zero-padded to the largest template; ``half_widths``: ``(S,) int64`` their ``L``;
- ``contract``: JSON of the :class:`~.core.ArrayContract` fields (weights as nested
  lists); ``point``: the design point's TOML text; ``meta``: JSON metadata.

A testbench loads it with :func:`load_stimulus`, configures the RTL from ``contract`` and
``thresholds``, drives ``codes`` step by step (pulsing ``clear`` before the listed steps)
and compares every spike.
"""

from __future__ import annotations

import dataclasses
import json
import os
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from rvsm.model.fixed.core import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.infra.atomic import atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.integrity import verify_npz
from rvsm.model.infra.npy_guard import check_npz_members
from rvsm.model.infra.versions import with_versions
from rvsm.model.scene.scene import Scene

STIMULUS_KEYS = (
    "codes", "thresholds", "spikes", "weights", "half_widths", "contract", "point", "meta",
)
OPTIONAL_KEYS = ("clear_before",)


@dataclass
class Stimulus:
    """Per-step ADC ``codes (T, H, W) uint16``, ``thresholds (S, H, W) int64``, expected
    ``spikes (T, S, H, W) int8``, the integer ``contract``, (when known) its point, and
    the steps ``clear_before`` which the array restarts from zero."""

    codes: np.ndarray
    thresholds: np.ndarray
    spikes: np.ndarray
    contract: ArrayContract
    point: DesignPoint | None = None
    meta: dict = field(default_factory=dict)
    clear_before: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        self.clear_before = tuple(sorted({int(t) for t in self.clear_before}))

    @property
    def num_steps(self) -> int:
        """T, the number of steps."""
        return int(self.codes.shape[0])

    def check(self) -> bool:
        """True when ``contract.run(codes, thresholds, clear_before)`` reproduces ``spikes``."""
        want = self.contract.run(self.codes, self.thresholds, self.clear_before)
        return bool(np.array_equal(want, self.spikes))

    def first_steps(self, steps: int) -> Stimulus:
        """The same stimulus cut to its first ``steps`` steps (clears beyond them dropped)."""
        return dataclasses.replace(
            self, codes=self.codes[:steps], spikes=self.spikes[:steps],
            clear_before=tuple(t for t in self.clear_before if t < steps),
        )


def make_stimulus(
    scene: Scene, point: DesignPoint, progress: bool = False, num_steps: int | None = None
) -> Stimulus:
    """Run the fixed twin on ``scene`` and keep its inputs and outputs.

    ``num_steps`` keeps only the first steps of the scene (a shorter testbench run).
    """
    if num_steps is not None:
        if isinstance(num_steps, bool) or int(num_steps) < 1:
            raise RvsmError(f"number of steps must be an integer >= 1, got {num_steps!r}")
        if num_steps > scene.num_steps:
            raise RvsmError(f"--steps {num_steps} is more than the {scene.num_steps} steps of "
                            f"scene {scene.name!r}; ask for at most {scene.num_steps}")
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
        out = Scene(scene.name, frames, m, True, scene.source)
    else:
        frames = scene.frames[: -(-steps // m) + 1]
        out = Scene(scene.name, frames, m, False, scene.source)
    if out.num_steps == steps:
        return out
    return Scene(scene.name, out.brightness(0, steps), 1, True, scene.source)


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
        "clear_before": np.asarray(stim.clear_before, dtype=np.int64).reshape(-1),
        "weights": weights,
        "half_widths": np.array([len(k) // 2 for k in c.weights], dtype=np.int64),
        "contract": np.array(json.dumps(asdict(c))),
        "point": np.array(design_point_toml(stim.point) if stim.point else ""),
        "meta": np.array(json.dumps(with_versions(stim.meta), sort_keys=True)),
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)


def load_stimulus(path: str | os.PathLike) -> Stimulus:
    """Read a stimulus file written by :func:`save_stimulus`."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"stimulus file {p} does not exist")
    check_npz_members(p, {"codes": 3, "thresholds": 3, "spikes": 4})
    verify_npz(p, "stimulus file")
    try:
        with np.load(p, allow_pickle=False) as data:
            missing = set(STIMULUS_KEYS) - set(data.files)
            if missing:
                raise RvsmError(
                    f"{p} is not an rvsm stimulus file: missing {', '.join(sorted(missing))}"
                )
            arrays = {k: data[k] for k in STIMULUS_KEYS + OPTIONAL_KEYS if k in data.files}
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
        clear_before=tuple(int(t) for t in arrays.get("clear_before", ())),
    )
