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

from rvsm.model.fixed.core import SENSORS, ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.fixed.widths import unsigned_max
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

    def with_recomputed_expectation(self) -> Stimulus:
        """The same stimulus with ``spikes`` recomputed from its own codes, thresholds,
        clears and contract (``rvsm verify --stimulus F --recompute-expected``)."""
        spikes = self.contract.run(self.codes, self.thresholds, self.clear_before)
        return dataclasses.replace(self, spikes=np.asarray(spikes, dtype=np.int8))

    def first_inconsistency(self) -> str | None:
        """Where the file's parts disagree with each other, or None: the point's contract
        against ``contract``; the expected ``spikes`` against what ``contract.run`` gives
        from ``codes``, ``thresholds`` and ``clear_before`` (the first step, scale, row and
        column that differ). Costs one fixed-twin run of the stimulus."""
        c = self.contract
        if self.point is not None:
            try:
                from_point = self.point.with_size(c.height, c.width).contract()
            except (RvsmError, ValueError, TypeError) as exc:
                return f"its design point cannot make a contract ({exc})"
            if from_point != c:
                return "its design point and its contract disagree"
        want_shape = (self.num_steps, c.num_scales, c.height, c.width)
        if self.spikes.shape != want_shape:
            return f"expected spikes have shape {self.spikes.shape}, the codes need {want_shape}"
        if self.thresholds.shape != want_shape[1:]:
            return f"thresholds have shape {self.thresholds.shape}, need {want_shape[1:]}"
        bad_clear = [t for t in self.clear_before if not 0 <= t < max(self.num_steps, 1)]
        if bad_clear:
            return f"clear_before step {bad_clear[0]} is outside 0..{self.num_steps - 1}"
        want = self.contract.run(self.codes, self.thresholds, self.clear_before)
        diff = np.argwhere(want != self.spikes)
        if diff.size == 0:
            return None
        t, sc, y, x = (int(v) for v in diff[0])
        return (f"{len(diff)} expected spikes do not follow from its codes, thresholds and "
                f"contract; the first at step {t}, scale {sc}, row {y}, column {x} (file "
                f"{int(self.spikes[t, sc, y, x])}, contract {int(want[t, sc, y, x])})")

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
        frames = scene.frame_range(0, -(-steps // m))
        out = Scene(scene.name, frames, m, True, scene.source)
    else:
        frames = scene.frame_range(0, -(-steps // m) + 1)
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
    check_npz_members(p, {"codes": 3, "thresholds": 3, "spikes": 4, "weights": None,
                          "half_widths": None, "contract": 0, "point": 0, "meta": 0,
                          "clear_before": None})
    verify_npz(p, "stimulus file")
    try:
        with np.load(p, allow_pickle=False) as data:
            missing = set(STIMULUS_KEYS) - set(data.files)
            if missing:
                raise RvsmError(
                    f"{p} is not an rvsm stimulus file: missing {', '.join(sorted(missing))}"
                )
            arrays = {k: data[k] for k in STIMULUS_KEYS + OPTIONAL_KEYS if k in data.files}
            odd = [k for k, v in arrays.items() if not isinstance(v, np.ndarray)]
            if odd:
                raise RvsmError(f"{p}: member {odd[0]!r} is not a .npy array; the file is "
                                f"damaged or not an rvsm stimulus file")
    except RvsmError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise RvsmError(f"{p} is not a readable stimulus file: {exc}") from None
    contract = _contract(arrays["contract"], str(p))
    point_text = _text(arrays["point"], "point", str(p))
    point = parse_design_point(point_text, str(p)) if point_text else None
    try:
        meta = json.loads(_text(arrays["meta"], "meta", str(p)))
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{p}: 'meta' is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RvsmError(f"{p}: 'meta' must be a JSON object")
    codes, thresholds, spikes, clears = _arrays(arrays, contract, str(p))
    return Stimulus(codes=codes, thresholds=thresholds, spikes=spikes, contract=contract,
                    point=point, meta=meta, clear_before=clears)


#: Bounds a stimulus file's contract must keep (what the RTL generator takes).
_CONTRACT_LIMITS = {"height": (1, 1 << 16), "width": (1, 1 << 16), "adc_bits": (1, 16),
                    "shift": (0, 62), "accumulator_bits": (2, 62)}
_RESETS = ("zero", "subtract")


def _text(value: np.ndarray, name: str, source: str) -> str:
    """A 0-d string member's text."""
    if value.ndim != 0 or value.dtype.kind not in "US":
        raise RvsmError(f"{source}: {name!r} must be a text scalar, got {value.dtype} "
                        f"{value.shape}")
    return str(value)


def _contract(value: np.ndarray, source: str) -> ArrayContract:
    """The file's ``contract`` member, checked field by field."""
    try:
        raw = json.loads(_text(value, "contract", source))
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{source}: 'contract' is not valid JSON ({exc})") from None
    fields = {f.name for f in dataclasses.fields(ArrayContract)}
    if not isinstance(raw, dict) or set(raw) - fields or \
            fields - {"reset", "sensor"} - set(raw):
        raise RvsmError(f"{source}: 'contract' must be an object with the fields "
                        f"{', '.join(sorted(fields))}")
    for name, (lo, hi) in _CONTRACT_LIMITS.items():
        v = raw[name]
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise RvsmError(f"{source}: contract {name} must be an integer in {lo}..{hi}, "
                            f"got {v!r}")
    if not isinstance(raw["signed"], bool) or raw.get("reset", "zero") not in _RESETS:
        raise RvsmError(f"{source}: contract signed must be true/false and reset one of "
                        f"{_RESETS}")
    if raw.get("sensor", "spike") not in SENSORS:
        raise RvsmError(f"{source}: contract sensor must be one of {SENSORS}, got "
                        f"{raw.get('sensor')!r}")
    raw["weights"] = _kernels(raw["weights"], source)
    return ArrayContract(**raw)


def _kernels(value: object, source: str) -> tuple:
    """Integer kernels: 1 to 4 odd square matrices of integers below 2**31 in size."""
    ok = isinstance(value, list) and 1 <= len(value) <= 4
    kernels = []
    for k in value if ok else ():
        n = len(k) if isinstance(k, list) else 0
        ok = ok and n % 2 == 1 and n <= 63 and all(
            isinstance(row, list) and len(row) == n and all(
                isinstance(v, int) and not isinstance(v, bool) and abs(v) < 1 << 31
                for v in row) for row in k)
        if ok:
            kernels.append(tuple(tuple(int(v) for v in row) for row in k))
    if not ok:
        raise RvsmError(f"{source}: contract weights must be 1 to 4 odd square matrices of "
                        f"integers")
    return tuple(kernels)


def _arrays(arrays: dict, c: ArrayContract, source: str) -> tuple:
    """``codes``, ``thresholds``, ``spikes`` and ``clear_before`` checked against the
    contract (shapes, integer dtypes, value ranges)."""
    codes, thresholds, spikes = arrays["codes"], arrays["thresholds"], arrays["spikes"]
    for name, arr in (("codes", codes), ("thresholds", thresholds), ("spikes", spikes)):
        if arr.dtype.kind not in "iu":
            raise RvsmError(f"{source}: {name!r} must hold integers, got {arr.dtype}")
    t = codes.shape[0] if codes.ndim == 3 else -1
    want = {"codes": (t, c.height, c.width), "thresholds": (c.num_scales, c.height, c.width),
            "spikes": (t, c.num_scales, c.height, c.width)}
    for name, arr in (("codes", codes), ("thresholds", thresholds), ("spikes", spikes)):
        if arr.shape != want[name]:
            raise RvsmError(f"{source}: {name!r} has shape {arr.shape}, the contract needs "
                            f"{want[name]}")
    if codes.size and (int(codes.min()) < 0 or int(codes.max()) > unsigned_max(c.adc_bits)):
        raise RvsmError(f"{source}: codes outside the {c.adc_bits}-bit ADC range")
    top = unsigned_max(c.threshold_bits)
    if thresholds.size and (int(thresholds.min()) < 0 or int(thresholds.max()) > top):
        raise RvsmError(f"{source}: thresholds outside 0..{top}")
    if spikes.size and (int(spikes.min()) < -1 or int(spikes.max()) > 1):
        raise RvsmError(f"{source}: expected spikes must lie in {{-1, 0, 1}}")
    clears = arrays.get("clear_before", np.zeros(0, np.int64))
    if clears.dtype.kind not in "iu" or clears.ndim != 1:
        raise RvsmError(f"{source}: 'clear_before' must be a 1-d integer array")
    return (codes, thresholds.astype(np.int64), spikes.astype(np.int8),
            tuple(int(v) for v in clears))
