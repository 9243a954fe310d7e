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
and compares every spike.

**Long runs, bounded memory.** :func:`write_stimulus` (``rvsm stimulus``) makes the file a
chunk of steps at a time: the ``codes`` member from the scene's brightness (+ dark
current) through the ADC, then the ``spikes`` member from the fused fixed twin, each
deflated into its zip member as it is made, so memory does not grow with the number of
steps; the arrays are those of :func:`make_stimulus` + :func:`save_stimulus` (same codes,
spikes, thresholds and ``meta``). :func:`open_stimulus` reads a file lazily: ``codes``
and ``spikes`` are :class:`MemberArray` s, inflated a range of steps at a time (a
sequential read never inflates a byte twice) and checked as they are read; every other
member is small and read whole. The format is unchanged (a zip of ``.npy`` members, any
deflate level or stored): files from before still load. Members are deflated at level
:data:`COMPRESS_LEVEL` (``np.savez_compressed`` uses 6): measured on 4,000 steps of
250x400 dog4, level 1 deflates codes at 86 MB/s (level 6: 16 MB/s) and spikes at 362
MB/s (97 MB/s) for files 1.2x larger; inflating runs at 196 (codes) and 677 (spikes)
MB/s whatever the level. An uncompressed archive (memory-mappable) would be 9x larger
(2.4 GB for those 4,000 steps, 24 GB per second of camera time), and reading is far from
the bottleneck (the long-run harness consumes about 20 MB/s).
"""

from __future__ import annotations

import dataclasses
import json
import os
import threading
import zipfile
import zlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import numpy.lib.format as npformat

from rvsm.model.fixed.contract import SENSORS, ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.atomic import atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.integrity import verify_npz
from rvsm.model.infra.memory import require_memory
from rvsm.model.infra.npy_guard import check_npz_members, npz_member_layout
from rvsm.model.infra.progress import progress_bar
from rvsm.model.infra.versions import with_versions
from rvsm.model.scene.scene import Scene

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
        return dataclasses.replace(self, codes=_whole(self.codes, np.uint16),
                                   spikes=_whole(self.spikes, np.int8))

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
        """Where the file's parts disagree with each other, or None: the point's contract
        against ``contract``; the expected ``spikes`` against what ``contract.run`` gives
        from ``codes``, ``thresholds`` and ``clear_before`` (the first step, scale, row and
        column that differ). Costs one fixed-twin run of the stimulus, chunk by chunk
        (bounded memory: a lazy stimulus is read a chunk of steps at a time)."""
        c = self.contract
        if self.point is not None:
            try:
                from_point = self.point.with_size(c.height, c.width).contract()
            except (RvsmError, ValueError, TypeError) as exc:
                return f"its design point cannot make a contract ({exc})"
            if from_point != c:
                return "its design point and its contract disagree"
        want_shape = (self.num_steps, c.num_scales, c.height, c.width)
        if tuple(self.spikes.shape) != want_shape:
            return (f"expected spikes have shape {tuple(self.spikes.shape)}, the codes need "
                    f"{want_shape}")
        if self.thresholds.shape != want_shape[1:]:
            return f"thresholds have shape {self.thresholds.shape}, need {want_shape[1:]}"
        bad_clear = [t for t in self.clear_before if not 0 <= t < max(self.num_steps, 1)]
        if bad_clear:
            return f"clear_before step {bad_clear[0]} is outside 0..{self.num_steps - 1}"
        count, first = 0, None
        for t0, _, want in self.expected_chunks():
            got = np.asarray(self.spikes[t0:t0 + len(want)])
            diff = np.argwhere(want != got)
            count += len(diff)
            if diff.size and first is None:
                b, sc, y, x = (int(v) for v in diff[0])
                first = (t0 + b, sc, y, x, int(got[b, sc, y, x]), int(want[b, sc, y, x]))
        if first is None:
            return None
        t, sc, y, x, have, want_v = first
        return (f"{count} expected spikes do not follow from its codes, thresholds and "
                f"contract; the first at step {t}, scale {sc}, row {y}, column {x} (file "
                f"{have}, contract {want_v})")

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


def _whole(arr, dtype) -> np.ndarray:
    """``arr`` in memory as ``dtype``."""
    return np.asarray(arr, dtype=dtype)


class MemberArray:
    """An ``.npy`` member of a zip archive (a stimulus file's ``codes`` or ``spikes``),
    read a range of its first axis at a time: ``a[t0:t1]`` inflates only those steps.

    Reading forward continues where the last read stopped (a sequential pass inflates
    the member once); reading backward restarts the member. ``check(chunk, t0)`` checks
    every range read (the values a stimulus file may hold). ``np.asarray(a)`` reads it
    whole (refused when it would not fit in memory). Safe to read from one thread at a
    time (a lock serialises reads).
    """

    def __init__(self, path: str | os.PathLike, member: str, shape: tuple[int, ...],
                 dtype: np.dtype, data_offset: int,
                 check: Callable[[np.ndarray, int], None] | None = None) -> None:
        self.path = Path(path)
        self.member = member
        self.shape = tuple(int(v) for v in shape)
        self.dtype = np.dtype(dtype)
        self.data_offset = int(data_offset)
        self.check = check
        self._row = int(np.prod(self.shape[1:], dtype=np.int64)) * self.dtype.itemsize
        self._lock = threading.Lock()
        self._archive: zipfile.ZipFile | None = None
        self._handle = None
        self._pos = 0

    @property
    def ndim(self) -> int:
        """Number of dimensions."""
        return len(self.shape)

    @property
    def size(self) -> int:
        """Number of elements."""
        return int(np.prod(self.shape, dtype=np.int64))

    @property
    def nbytes(self) -> int:
        """Bytes of the whole array."""
        return self.size * self.dtype.itemsize

    def __len__(self) -> int:
        return self.shape[0]

    def __repr__(self) -> str:
        return f"MemberArray({str(self.path)!r}, {self.member!r}, {self.shape}, {self.dtype})"

    def head(self, steps: int) -> MemberArray:
        """The first ``steps`` entries, still read on demand."""
        steps = max(0, min(int(steps), self.shape[0]))
        return MemberArray(self.path, self.member, (steps, *self.shape[1:]), self.dtype,
                           self.data_offset, self.check)

    def __getitem__(self, key):
        rest = ()
        if isinstance(key, tuple):
            key, rest = (key[0], key[1:]) if key else (slice(None), ())
        if isinstance(key, slice):
            start, stop, step = key.indices(self.shape[0])
            out = self.read(start, max(start, stop))[::step] if step > 0 else \
                np.asarray(self)[key]
        elif isinstance(key, (int, np.integer)):
            k = int(key) + (self.shape[0] if key < 0 else 0)
            if not 0 <= k < self.shape[0]:
                raise IndexError(f"index {key} out of range for {self.shape[0]} steps")
            out = self.read(k, k + 1)[0]
        else:
            out = np.asarray(self)[key]
        return out[rest] if rest else out

    def __array__(self, dtype=None, copy=None):
        require_memory(self.nbytes, f"{self.path}: {self.member!r} {self.shape}",
                       "read it a range of steps at a time")
        out = self.read(0, self.shape[0])
        return out if dtype is None else out.astype(dtype, copy=False)

    def read(self, t0: int, t1: int) -> np.ndarray:
        """Entries ``t0 .. t1 - 1`` of the first axis, a new array."""
        if not 0 <= t0 <= t1 <= self.shape[0]:
            raise RvsmError(f"{self.path}: steps {t0}..{t1} outside 0..{self.shape[0]}")
        out = np.empty((t1 - t0, *self.shape[1:]), dtype=self.dtype)
        if out.nbytes:
            with self._lock:
                try:
                    self._seek(t0)
                    self._fill(memoryview(out.reshape(-1).view(np.uint8)))
                except (zipfile.BadZipFile, zlib.error, OSError, EOFError, ValueError,
                        NotImplementedError, RuntimeError) as exc:
                    self.close()
                    raise RvsmError(f"{self.path} is corrupt: member {self.member!r} of the "
                                    f"stimulus file cannot be read ({exc})") from None
                self._pos = t1
        if self.check is not None:
            self.check(out, t0)
        return out

    def _seek(self, t0: int) -> None:
        if self._handle is None or t0 < self._pos:
            self.close()
            self._archive = zipfile.ZipFile(self.path)
            self._handle = self._archive.open(self.member)
            self._skip(self.data_offset)
            self._pos = 0
        self._skip((t0 - self._pos) * self._row)
        self._pos = t0

    def _skip(self, nbytes: int) -> None:
        while nbytes > 0:
            got = self._handle.read(min(nbytes, 1 << 20))
            if not got:
                raise EOFError(f"{nbytes} bytes missing")
            nbytes -= len(got)

    def _fill(self, view: memoryview) -> None:
        done = 0
        while done < len(view):
            got = self._handle.readinto(view[done:])
            if not got:
                raise EOFError(f"{len(view) - done} bytes missing")
            done += got

    def close(self) -> None:
        """Close the open member (reads open it again)."""
        if self._handle is not None:
            self._handle.close()
        if self._archive is not None:
            self._archive.close()
        self._handle = self._archive = None
        self._pos = 0

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.update(_lock=None, _archive=None, _handle=None, _pos=0)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()


def _check_steps(scene: Scene, num_steps: int | None) -> Scene:
    """``scene`` cut to its first ``num_steps`` steps (checked)."""
    if num_steps is not None:
        if isinstance(num_steps, bool) or int(num_steps) < 1:
            raise RvsmError(f"number of steps must be an integer >= 1, got {num_steps!r}")
        if num_steps > scene.num_steps:
            raise RvsmError(f"--steps {num_steps} is more than the {scene.num_steps} steps of "
                            f"scene {scene.name!r}; ask for at most {scene.num_steps}")
        if num_steps < scene.num_steps:
            scene = _first_steps(scene, int(num_steps))
    return scene


def make_stimulus(
    scene: Scene, point: DesignPoint, progress: bool = False, num_steps: int | None = None
) -> Stimulus:
    """Run the fixed twin on ``scene`` and keep its inputs and outputs, in memory (a long
    run: :func:`write_stimulus`).

    ``num_steps`` keeps only the first steps of the scene (a shorter testbench run).
    """
    scene = _check_steps(scene, num_steps)
    run = simulate_fixed(scene, point, progress=progress, keep_codes=True)
    assert run.codes is not None
    meta = dict(run.meta, kind="stimulus")
    return Stimulus(run.codes, run.thresholds, run.spikes, run.contract, run.point, meta)


@dataclass(frozen=True)
class _StepFrames:
    """A frame per step: the brightness of ``scene``'s first ``steps`` steps, read on
    demand (a scene of them, held for one step each, has exactly those steps)."""

    scene: Scene
    steps: int

    @property
    def shape(self) -> tuple[int, int, int]:
        return (self.steps, *self.scene.shape)

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        return self.scene.brightness(f0, f1)


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
    return Scene(scene.name, _StepFrames(out, steps), 1, True, scene.source)


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
    scene = _check_steps(scene, num_steps)
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


_MEMBER_DIMS = {"codes": 3, "thresholds": 3, "spikes": 4, "weights": None,
                "half_widths": None, "contract": 0, "point": 0, "meta": 0,
                "clear_before": None}


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
    check_npz_members(p, _MEMBER_DIMS, lazy=LAZY_KEYS)
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
    contract = _contract(arrays["contract"], str(p))
    point_text = _text(arrays["point"], "point", str(p))
    point = parse_design_point(point_text, str(p)) if point_text else None
    try:
        meta = json.loads(_text(arrays["meta"], "meta", str(p)))
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{p}: 'meta' is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RvsmError(f"{p}: 'meta' must be a JSON object")
    for k in LAZY_KEYS:
        layout = arrays[k]
        if layout.fortran_order and len(layout.shape) > 1:
            raise RvsmError(f"{p}: {k!r} is stored in Fortran order; rvsm stimulus files "
                            f"are C-ordered (write it again with save_stimulus)")
        arrays[k] = MemberArray(p, f"{k}.npy", layout.shape, layout.dtype, layout.offset,
                                _value_check(k, contract, str(p)))
    codes, thresholds, spikes, clears = _arrays(arrays, contract, str(p))
    return Stimulus(codes=codes, thresholds=thresholds, spikes=spikes, contract=contract,
                    point=point, meta=meta, clear_before=clears)


def _value_check(name: str, c: ArrayContract, source: str
                 ) -> Callable[[np.ndarray, int], None]:
    """The check of every range of ``codes`` or ``spikes`` read from a file."""
    top = unsigned_max(c.adc_bits)

    def codes(chunk: np.ndarray, t0: int) -> None:
        if chunk.size and (int(chunk.min()) < 0 or int(chunk.max()) > top):
            raise RvsmError(f"{source}: codes outside the {c.adc_bits}-bit ADC range")

    def spikes(chunk: np.ndarray, t0: int) -> None:
        if chunk.size and (int(chunk.min()) < -1 or int(chunk.max()) > 1):
            raise RvsmError(f"{source}: expected spikes must lie in {{-1, 0, 1}}")

    return codes if name == "codes" else spikes


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
    contract (shapes, integer dtypes, value ranges: those of a :class:`MemberArray` as
    it is read)."""
    codes, thresholds, spikes = arrays["codes"], arrays["thresholds"], arrays["spikes"]
    for name, arr in (("codes", codes), ("thresholds", thresholds), ("spikes", spikes)):
        if arr.dtype.kind not in "iu":
            raise RvsmError(f"{source}: {name!r} must hold integers, got {arr.dtype}")
    t = codes.shape[0] if codes.ndim == 3 else -1
    want = {"codes": (t, c.height, c.width), "thresholds": (c.num_scales, c.height, c.width),
            "spikes": (t, c.num_scales, c.height, c.width)}
    for name, arr in (("codes", codes), ("thresholds", thresholds), ("spikes", spikes)):
        if tuple(arr.shape) != want[name]:
            raise RvsmError(f"{source}: {name!r} has shape {tuple(arr.shape)}, the contract needs "
                            f"{want[name]}")
    if not isinstance(codes, MemberArray):
        _value_check("codes", c, source)(codes, 0)
    top = unsigned_max(c.threshold_bits)
    if thresholds.size and (int(thresholds.min()) < 0 or int(thresholds.max()) > top):
        raise RvsmError(f"{source}: thresholds outside 0..{top}")
    if not isinstance(spikes, MemberArray):
        _value_check("spikes", c, source)(spikes, 0)
        spikes = spikes.astype(np.int8)
    clears = arrays.get("clear_before", np.zeros(0, np.int64))
    if clears.dtype.kind not in "iu" or clears.ndim != 1:
        raise RvsmError(f"{source}: 'clear_before' must be a 1-d integer array")
    return codes, thresholds.astype(np.int64), spikes, tuple(int(v) for v in clears)
