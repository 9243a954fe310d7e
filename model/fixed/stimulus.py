"""RTL stimulus: exactly what the fixed twin saw, and what it answered (SPEC section 5).

One format from the fixed twin to the RTL: ``rvsm stimulus`` writes it, the cocotb
testbench (:mod:`rvsm.sim.cosim.testbenches.tb_parallel`) drives the RTL from it, and
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
and compares every spike. This module is the format: :class:`Stimulus`, its writers and
its opener. :func:`open_stimulus` reads ``codes`` and ``spikes`` lazily, a range of steps
at a time (:class:`~.stimulus_reader.MemberArray`), and checks every member before use
(:mod:`.stimulus_validation`).

**Long runs, bounded memory.** :func:`write_stimulus` (``rvsm stimulus``) makes the file a
chunk of steps at a time: ``codes`` from the scene's brightness (+ dark current) through
the ADC, then ``spikes`` from the fused fixed twin, each deflated into its zip member as
it is made; the arrays are those of :func:`make_stimulus` + :func:`save_stimulus`. Any
deflate level (or stored) reads: files from before still load. Members are deflated at
level :data:`COMPRESS_LEVEL` (``np.savez_compressed`` uses 6): on 4,000 steps of 250x400
dog4, level 1 deflates codes at 86 MB/s (level 6: 16) and spikes at 362 MB/s (97) for
files 1.2x larger (2.4 GB uncompressed for those steps, 24 GB per second of camera time).
"""

from __future__ import annotations

import dataclasses
import json
import os
import zipfile
import zlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import numpy.lib.format as npformat

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.fixed.stimulus_reader import MemberArray
from rvsm.model.fixed.stimulus_validation import (
    MEMBER_DIMS,
    check_c_order,
    checked_arrays,
    first_inconsistency,
    member_contract,
    member_meta,
    member_text,
    value_check,
)
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.infra.atomic import atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.integrity import verify_npz
from rvsm.model.infra.memory import require_memory
from rvsm.model.infra.npy_guard import check_npz_members, npz_member_layout
from rvsm.model.infra.progress import progress_bar
from rvsm.model.infra.versions import with_versions
from rvsm.model.scene.scene import Scene
from rvsm.model.scene.scene_steps import scene_steps

STIMULUS_KEYS = (
    "codes", "thresholds", "spikes", "weights", "half_widths", "contract", "point", "meta",
)
OPTIONAL_KEYS = ("clear_before",)
#: Members read a range of steps at a time by :func:`open_stimulus`.
LAZY_KEYS = ("codes", "spikes")
#: Deflate level of the members :func:`write_stimulus` and :func:`save_stimulus` write
#: (module docstring: the measurement).
COMPRESS_LEVEL = 1
#: Steps read or written at a time by the chunked paths (codes and spikes of 64 steps of
#: 250x400 dog4: 38 MB).
IO_CHUNK_STEPS = 64


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

    @property
    def lazy(self) -> bool:
        """True when ``codes`` or ``spikes`` is read from its file on demand
        (:func:`open_stimulus`)."""
        return isinstance(self.codes, MemberArray) or isinstance(self.spikes, MemberArray)

    def loaded(self) -> Stimulus:
        """This stimulus with ``codes`` and ``spikes`` in memory (a lazy one's read whole;
        :class:`RvsmError` naming ``--harness chunk`` when they would not fit)."""
        if not self.lazy:
            return self
        require_memory(self.codes.nbytes + self.spikes.nbytes,
                       f"a stimulus of {self.num_steps} steps read whole",
                       "replay it in the long-run harness (--harness chunk), which reads "
                       "it a chunk of steps at a time")
        return dataclasses.replace(self, codes=np.asarray(self.codes, dtype=np.uint16),
                                   spikes=np.asarray(self.spikes, dtype=np.int8))

    def step_ranges(self, chunk_steps: int = IO_CHUNK_STEPS) -> Iterator[tuple[int, int, bool]]:
        """``(t0, t1, clear)``: consecutive ranges of at most ``chunk_steps`` steps, never
        across a clear; ``clear`` when the array is cleared before step ``t0``."""
        yield from step_ranges(self.num_steps, self.clear_before, chunk_steps)

    def expected_chunks(self, chunk_steps: int = IO_CHUNK_STEPS
                        ) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """``(t0, codes, spikes)`` chunk by chunk, the spikes being what ``contract.run``
        gives from ``codes``, ``thresholds`` and ``clear_before`` (the contract run
        chunk by chunk, :class:`~.core.ContractStream`: bounded memory)."""
        stream = self.contract.stream(self.thresholds)
        for t0, t1, clear in self.step_ranges(chunk_steps):
            if clear:
                stream.clear()
            codes = np.asarray(self.codes[t0:t1])
            yield t0, codes, stream.run(codes)

    def check(self) -> bool:
        """True when ``contract.run(codes, thresholds, clear_before)`` reproduces ``spikes``
        (chunk by chunk)."""
        return all(np.array_equal(want, np.asarray(self.spikes[t0:t0 + len(want)]))
                   for t0, _, want in self.expected_chunks())

    def with_recomputed_expectation(self) -> Stimulus:
        """The same stimulus with ``spikes`` recomputed from its own codes, thresholds,
        clears and contract (``rvsm verify --stimulus F --recompute-expected``), in
        memory."""
        spikes = np.empty((self.num_steps, self.contract.num_scales, self.contract.height,
                           self.contract.width), dtype=np.int8)
        for t0, _, want in self.expected_chunks():
            spikes[t0:t0 + len(want)] = want
        return dataclasses.replace(self, spikes=spikes)

    def first_inconsistency(self) -> str | None:
        """Where the file's parts disagree with each other, or None
        (:func:`~.stimulus_validation.first_inconsistency`: one fixed-twin run of the
        stimulus, chunk by chunk)."""
        return first_inconsistency(self)

    def first_steps(self, steps: int) -> Stimulus:
        """The same stimulus cut to its first ``steps`` steps (clears beyond them dropped;
        a lazy stimulus stays lazy)."""
        return dataclasses.replace(
            self, codes=_head(self.codes, steps), spikes=_head(self.spikes, steps),
            clear_before=tuple(t for t in self.clear_before if t < steps),
        )


def step_ranges(num_steps: int, clear_before: Iterable[int], chunk_steps: int
                ) -> Iterator[tuple[int, int, bool]]:
    """``(t0, t1, clear)``: consecutive ranges of ``0 .. num_steps`` of at most
    ``chunk_steps`` steps, cut at every clear inside the run; ``clear`` when the array is
    cleared before step ``t0``."""
    if isinstance(chunk_steps, bool) or int(chunk_steps) < 1:
        raise RvsmError(f"chunk steps must be >= 1, got {chunk_steps}")
    cuts = sorted({int(t) for t in clear_before if 0 < int(t) < num_steps})
    bounds = [0, *cuts, num_steps]
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        for t0 in range(a, b, int(chunk_steps)):
            yield t0, min(t0 + int(chunk_steps), b), bool(t0 == a and a > 0)


def _head(arr, steps: int):
    """The first ``steps`` steps of an array or a :class:`MemberArray` (still lazy)."""
    return arr.head(steps) if isinstance(arr, MemberArray) else arr[:steps]


def make_stimulus(
    scene: Scene, point: DesignPoint, progress: bool = False, num_steps: int | None = None
) -> Stimulus:
    """Run the fixed twin on ``scene`` and keep its inputs and outputs, in memory (a long
    run: :func:`write_stimulus`).

    ``num_steps`` keeps only the first steps of the scene (a shorter testbench run).
    """
    scene = scene_steps(scene, num_steps)
    run = simulate_fixed(scene, point, progress=progress, keep_codes=True)
    assert run.codes is not None
    meta = dict(run.meta, kind="stimulus")
    return Stimulus(run.codes, run.thresholds, run.spikes, run.contract, run.point, meta)


def _padded_weights(c: ArrayContract) -> np.ndarray:
    big = max(len(k) for k in c.weights)
    weights = np.zeros((c.num_scales, big, big), dtype=np.int64)
    for s, k in enumerate(c.weight_arrays):
        off = (big - k.shape[0]) // 2
        weights[s, off:off + k.shape[0], off:off + k.shape[0]] = k
    return weights


def _write_small(archive: zipfile.ZipFile, name: str, value: np.ndarray) -> None:
    """One whole ``.npy`` member (as ``np.savez`` writes it)."""
    with archive.open(f"{name}.npy", "w", force_zip64=True) as handle:
        npformat.write_array(handle, np.asanyarray(value), allow_pickle=False)


def _write_chunks(archive: zipfile.ZipFile, name: str, shape: tuple[int, ...], dtype,
                  chunks: Iterable[np.ndarray]) -> None:
    """One ``.npy`` member of ``shape`` written from ``chunks`` along its first axis."""
    dtype = np.dtype(dtype)
    rows = 0
    with archive.open(f"{name}.npy", "w", force_zip64=True) as handle:
        npformat.write_array_header_1_0(handle, {"descr": npformat.dtype_to_descr(dtype),
                                                 "fortran_order": False,
                                                 "shape": tuple(int(v) for v in shape)})
        for chunk in chunks:
            part = np.ascontiguousarray(chunk, dtype=dtype)
            if part.shape[1:] != tuple(shape[1:]):
                raise RvsmError(f"stimulus {name}: chunk of shape {part.shape} for an array "
                                f"of shape {tuple(shape)}")
            rows += part.shape[0]
            handle.write(memoryview(part.reshape(-1).view(np.uint8)))
    if rows != shape[0]:
        raise RvsmError(f"stimulus {name}: {rows} steps written for {shape[0]}")


def _write_file(path: str | os.PathLike, contract: ArrayContract, thresholds: np.ndarray,
                num_steps: int, codes: Iterable[np.ndarray],
                spikes: Callable[[], Iterable[np.ndarray]], clear_before: Iterable[int],
                point: DesignPoint | None, meta: Callable[[], dict]) -> None:
    """The stimulus file, atomically, its large members from chunks (module docstring):
    ``codes`` is iterated first, then ``spikes()``; ``meta()`` is asked last."""
    c = contract
    if c.adc_bits > 16:
        raise RvsmError(f"stimulus files hold 16-bit codes; adc.bits = {c.adc_bits} > 16")
    plane = (c.height, c.width)
    with atomic_path(path) as tmp, \
            zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED,
                            compresslevel=COMPRESS_LEVEL) as archive:
        _write_chunks(archive, "codes", (num_steps, *plane), np.uint16, codes)
        _write_small(archive, "thresholds", np.asarray(thresholds, dtype=np.int64))
        _write_chunks(archive, "spikes", (num_steps, c.num_scales, *plane), np.int8,
                      spikes())
        _write_small(archive, "clear_before",
                     np.asarray(tuple(clear_before), dtype=np.int64).reshape(-1))
        _write_small(archive, "weights", _padded_weights(c))
        _write_small(archive, "half_widths",
                     np.array([len(k) // 2 for k in c.weights], dtype=np.int64))
        _write_small(archive, "contract", np.array(json.dumps(asdict(c))))
        _write_small(archive, "point", np.array(design_point_toml(point) if point else ""))
        _write_small(archive, "meta",
                     np.array(json.dumps(with_versions(meta()), sort_keys=True)))


def save_stimulus(path: str | os.PathLike, stim: Stimulus) -> None:
    """Write ``stim`` as ``.npz`` (keys in the module docstring), atomically, a chunk of
    steps at a time (a lazy stimulus is copied in bounded memory)."""
    steps = [(t0, min(t0 + IO_CHUNK_STEPS, stim.num_steps))
             for t0 in range(0, stim.num_steps, IO_CHUNK_STEPS)]
    _write_file(path, stim.contract, stim.thresholds, stim.num_steps,
                (stim.codes[a:b] for a, b in steps),
                lambda: (stim.spikes[a:b] for a, b in steps), stim.clear_before,
                stim.point, lambda: stim.meta)


@dataclass(frozen=True)
class StimulusSummary:
    """What :func:`write_stimulus` wrote: ``shape (T, S, H, W)`` and the non-zero
    expected ``spikes``."""

    shape: tuple[int, int, int, int]
    spikes: int


def write_stimulus(
    path: str | os.PathLike, scene: Scene, point: DesignPoint, progress: bool = False,
    num_steps: int | None = None, chunk_steps: int = IO_CHUNK_STEPS,
) -> StimulusSummary:
    """``save_stimulus(path, make_stimulus(scene, point, progress, num_steps))`` in
    bounded memory (``rvsm stimulus``): the same arrays and ``meta``, made and written
    ``chunk_steps`` steps at a time, the codes first (scene brightness, dark current,
    ADC), then the expected spikes (the fused fixed twin, whose spikes and saturation
    counts are the numpy engine's; the event sensor's numpy twin)."""
    from rvsm.model.fixed.numpy_engine import step_codes
    from rvsm.model.fixed.results import FixedStats, fixed_meta
    from rvsm.model.fixed.twin import fit_point, make_twin

    if isinstance(chunk_steps, bool) or int(chunk_steps) < 1:
        raise RvsmError(f"chunk steps must be >= 1, got {chunk_steps!r}")
    scene = scene_steps(scene, num_steps)
    point = fit_point(scene, point)
    thresholds = point.integer_thresholds(point.noise_source())
    contract = point.contract()
    total, (h, w), s_count = scene.num_steps, point.shape, point.num_scales
    ranges = [(t0, min(t0 + int(chunk_steps), total)) for t0 in range(0, total, chunk_steps)]
    state: dict = {"nonzero": 0}

    def codes() -> Iterator[np.ndarray]:
        noise = point.noise_source()
        bar = progress_bar(total, f"codes {scene.name}", progress)
        try:
            for t0, t1 in ranges:
                yield step_codes(scene, point, noise, t0, t1)
                bar.update(t1 - t0)
        finally:
            bar.close()

    def spikes() -> Iterator[np.ndarray]:
        twin = state["twin"] = make_twin(scene, point, thresholds, "fused", ranges=False)
        buf = np.empty((min(int(chunk_steps), max(total, 1)), s_count, h, w), np.int8)
        bar = progress_bar(total, f"fixed {point.model} {scene.name}", progress)
        try:
            for t0, t1 in ranges:
                out = twin.run(t0, t1, buf[:t1 - t0])
                state["nonzero"] += int(np.count_nonzero(out))
                yield out
                bar.update(t1 - t0)
        finally:
            bar.close()

    def meta() -> dict:
        stats = FixedStats(steps=total, accumulators=h * w, **state["twin"].stats())
        return dict(fixed_meta(scene, point, thresholds, stats), kind="stimulus")

    _write_file(path, contract, thresholds, total, codes(), spikes, (), point, meta)
    return StimulusSummary((total, s_count, h, w), state["nonzero"])


def load_stimulus(path: str | os.PathLike) -> Stimulus:
    """Read a stimulus file written by :func:`save_stimulus` or :func:`write_stimulus`,
    whole (refused when it would not fit in memory; :func:`open_stimulus` reads it a
    chunk of steps at a time)."""
    return open_stimulus(path).loaded()


def open_stimulus(path: str | os.PathLike) -> Stimulus:
    """Open a stimulus file lazily: its ``codes`` and ``spikes`` are
    :class:`MemberArray` s read a range of steps at a time (and checked as they are
    read: codes in the ADC range, spikes in {-1, 0, 1}); everything else is read and
    checked now, as is every member's CRC (:func:`~rvsm.model.infra.integrity.verify_npz`,
    1 MiB at a time). Any file :func:`load_stimulus` ever read opens (the format has not
    changed; the deflate level does not matter)."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"stimulus file {p} does not exist")
    check_npz_members(p, MEMBER_DIMS, lazy=LAZY_KEYS)
    verify_npz(p, "stimulus file")
    try:
        with zipfile.ZipFile(p) as archive:
            members = {n[:-4] for n in archive.namelist() if n.endswith(".npy")}
            missing = set(STIMULUS_KEYS) - members
            if missing:
                raise RvsmError(
                    f"{p} is not an rvsm stimulus file: missing {', '.join(sorted(missing))}"
                )
            arrays: dict = {}
            for k in STIMULUS_KEYS + OPTIONAL_KEYS:
                if k not in members:
                    continue
                info = archive.getinfo(f"{k}.npy")
                if k in LAZY_KEYS:
                    arrays[k] = npz_member_layout(archive, info, f"{p}: {k!r}")
                else:
                    with archive.open(info) as handle:
                        arrays[k] = npformat.read_array(handle, allow_pickle=False)
    except RvsmError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, zlib.error) as exc:
        raise RvsmError(f"{p} is not a readable stimulus file: {exc}") from None
    contract = member_contract(arrays["contract"], str(p))
    point_text = member_text(arrays["point"], "point", str(p))
    point = parse_design_point(point_text, str(p)) if point_text else None
    meta = member_meta(arrays["meta"], str(p))
    for k in LAZY_KEYS:
        layout = arrays[k]
        check_c_order(k, layout.fortran_order, layout.shape, str(p))
        arrays[k] = MemberArray(p, f"{k}.npy", layout.shape, layout.dtype, layout.offset,
                                value_check(k, contract, str(p)))
    codes, thresholds, spikes, clears = checked_arrays(arrays, contract, str(p))
    return Stimulus(codes=codes, thresholds=thresholds, spikes=spikes, contract=contract,
                    point=point, meta=meta, clear_before=clears)

