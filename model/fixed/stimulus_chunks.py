"""Stimulus a chunk of steps at a time: what a long co-simulation run drives and expects,
in bounded memory.

A :class:`StimulusChunks` gives the ADC codes ``(B, H, W) uint16`` and the expected spikes
``(B, S, H, W) int8`` of consecutive step ranges, plus the thresholds and clears: the
content of a :class:`~.stimulus.Stimulus` without ever holding all of it. Two sources:

* :meth:`StimulusChunks.from_stimulus`: slices of a stimulus, in memory or a file read
  a range of steps at a time (:func:`~.stimulus.open_stimulus`: bounded memory however
  long the file), optionally with the expectation recomputed from its codes chunk by
  chunk (:class:`~.core.ContractStream`);
* :meth:`StimulusChunks.from_scene`: a scene through a design point, produced on demand:
  brightness of the chunk's steps (+ the point's dark current, same streams as the
  twins), its ADC codes (:func:`~.numpy_engine.step_codes`), and the expectation from
  the fixed twin run chunk by chunk: the fused engine (:class:`~.fused.FusedFixedTwin`,
  default: 0.1 ms per step at 250x400 against 20 ms) or ``engine="numpy"``, the integer
  contract itself on those codes (:class:`~.core.ContractStream`, the arithmetic of
  :meth:`ArrayContract.run`). Both give the same spikes (the twins' oracle tests, and
  this module's own).

A run crosses process boundaries as a small JSON description (:meth:`spec`,
:func:`open_stimulus_chunks`): a stimulus file, or a scene argument, a design point's
TOML text and a number of steps.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.fused import FusedFixedTwin
from rvsm.model.fixed.numpy_engine import step_codes
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.fixed.sensor_rules import sensor_rules
from rvsm.model.fixed.stimulus import Stimulus, open_stimulus, step_ranges
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene

__all__ = ["StimulusChunk", "StimulusChunks", "open_stimulus_chunks"]


@dataclass(frozen=True)
class StimulusChunk:
    """Steps ``t0 .. t0 + B - 1``: ``codes (B, H, W) uint16``, expected ``spikes (B, S, H,
    W) int8``; ``clear`` when the array is cleared before step ``t0``."""

    t0: int
    codes: np.ndarray
    spikes: np.ndarray
    clear: bool = False

    @property
    def num_steps(self) -> int:
        """B, the steps of this chunk."""
        return int(self.codes.shape[0])


@dataclass
class StimulusChunks:
    """A run's ``contract``, ``thresholds (S, H, W) int64``, ``num_steps``, the steps
    ``clear_before`` which the array restarts from zero, and its chunks (:meth:`chunks`).
    ``spec`` describes how to open it again (:func:`open_stimulus_chunks`; empty when
    it cannot be: a scene made in code); ``stimulus`` is the stimulus the chunks are cut
    from (:meth:`from_stimulus`; in memory, or lazy: read from its file a chunk at a
    time), else None."""

    contract: ArrayContract
    thresholds: np.ndarray
    num_steps: int
    clear_before: tuple[int, ...] = ()
    spec: dict = field(default_factory=dict)
    stimulus: Stimulus | None = field(default=None, repr=False)  # when held in memory
    _scene: Scene | None = field(default=None, repr=False)
    _point: DesignPoint | None = field(default=None, repr=False)
    _engine: str = field(default="fused", repr=False)
    _recompute: bool = field(default=False, repr=False)
    _engine_state: object = field(default=None, init=False, repr=False)
    _start_state: np.ndarray | None = field(default=None, init=False, repr=False)

    @classmethod
    def from_stimulus(cls, stim: Stimulus, path: str | None = None,
                      recompute: bool = False) -> StimulusChunks:
        """Chunks of ``stim`` (``path``: the file it was read from, for :attr:`spec`; ``stim``
        may be its first steps). ``recompute`` takes the expected spikes from its codes
        (the integer contract run chunk by chunk) instead of its ``spikes``."""
        spec = {}
        if path:
            spec = {"kind": "stimulus", "path": path, "steps": stim.num_steps,
                    "recompute": bool(recompute)}
        return cls(stim.contract, np.asarray(stim.thresholds, dtype=np.int64),
                   stim.num_steps, tuple(stim.clear_before), spec, stimulus=stim,
                   _recompute=bool(recompute))

    @classmethod
    def from_scene(cls, scene: Scene, point: DesignPoint, num_steps: int | None = None,
                   engine: str = "fused") -> StimulusChunks:
        """The first ``num_steps`` (default all) steps of ``scene`` through ``point``
        (sized to the scene), no clears; ``engine`` (``"fused"`` or ``"numpy"``) makes
        the expectation."""
        if engine not in ("fused", "numpy"):
            raise RvsmError(f"engine must be 'fused' or 'numpy', got {engine!r}")
        if scene.shape != point.shape:
            point = point.with_size(*scene.shape)
        steps = scene.num_steps if num_steps is None else int(num_steps)
        if not 1 <= steps <= scene.num_steps:
            raise RvsmError(f"number of steps must be 1..{scene.num_steps} for scene "
                            f"{scene.name!r}, got {num_steps!r}")
        spec = {}
        if scene.source is not None:
            spec = {"kind": "scene", "scene": scene.source, "size": list(scene.shape),
                    "num_frames": scene.num_frames,
                    "steps_per_frame": scene.steps_per_frame, "hold": scene.hold,
                    "point": design_point_toml(point), "steps": steps, "engine": engine}
        thresholds = point.integer_thresholds(point.noise_source())
        return cls(point.contract(), thresholds, steps, (), spec, _scene=scene,
                   _point=point, _engine=engine)

    def chunks(self, chunk_steps: int, start: int = 0, stop: int | None = None
               ) -> Iterator[StimulusChunk]:
        """Consecutive chunks of at most ``chunk_steps`` steps, never across a clear.

        ``start`` / ``stop`` (a segment of a sharded run): only steps ``start .. stop -
        1`` are yielded; the twin is first run over steps ``0 .. start - 1`` without
        yielding them (the state at ``start`` is a function of the steps before it
        only): :meth:`start_state` is the twin's state at ``start``. After the
        generator has yielded a chunk, :meth:`state` is the state after its last
        step."""
        tracked = start > 0 or stop is not None  # a segment: its states are asked for
        stop = self.num_steps if stop is None else int(stop)
        if not 0 <= int(start) < stop <= self.num_steps:
            raise RvsmError(f"segment {start}..{stop} is not inside 0..{self.num_steps}")
        ranges = step_ranges(self.num_steps, self.clear_before, chunk_steps)
        # a segment of a stimulus runs the contract for its state (the file's spikes
        # stay the expectation)
        segment = self.stimulus is not None and tracked
        stream = twin = None
        fused = sensor_rules(self.contract.kind).fused_twin  # not the event sensor
        if (self._engine == "numpy" or not fused) and self.stimulus is None \
                or self._recompute or segment:
            stream = self.contract.stream(self.thresholds)
        elif self.stimulus is None:
            assert self._scene is not None and self._point is not None
            if any(0 < t < self.num_steps for t in self.clear_before):
                raise RvsmError("the fused engine runs scenes without clears")
            twin = FusedFixedTwin(self._scene, self._point, self.thresholds, ranges=False)
        self._engine_state = twin if twin is not None else stream
        noise = self._point.noise_source() if self._point is not None else None
        for t0, t1, clear in self._cut(ranges, int(start), stop):
            if stream is not None and clear:
                stream.clear()
            skip = t1 <= start  # before the segment: state only
            if t0 == start and self._engine_state is not None:
                self._start_state = self.state()
            if self.stimulus is not None:
                codes = np.asarray(self.stimulus.codes[t0:t1])
                spikes = (stream.run(codes) if stream is not None
                          else self.stimulus.spikes[t0:t1])
                if segment and not self._recompute:
                    spikes = self.stimulus.spikes[t0:t1]
            else:
                assert self._scene is not None and self._point is not None
                if skip and twin is not None:
                    twin.run(t0, t1)
                    continue
                codes = step_codes(self._scene, self._point, noise, t0, t1)
                spikes = (twin.run(t0, t1) if twin is not None
                          else stream.run(codes))  # type: ignore[union-attr]
            if skip:
                continue
            yield StimulusChunk(t0, np.asarray(codes, dtype=np.uint16),
                                np.asarray(spikes, dtype=np.int8), clear=clear)

    @staticmethod
    def _cut(ranges: Iterator[tuple[int, int, bool]], start: int, stop: int
             ) -> Iterator[tuple[int, int, bool]]:
        """The ranges cut at ``start`` and ended at ``stop``."""
        for t0, t1, clear in ranges:
            if t0 >= stop:
                return
            t1 = min(t1, stop)
            if t1 <= start:
                yield t0, t1, clear
            elif t0 < start:
                yield t0, start, clear
                yield start, t1, False
            else:
                yield t0, t1, clear

    def start_state(self) -> np.ndarray:
        """The twin's state ``(S, H, W) int64`` at the ``start`` of the last
        :meth:`chunks` (known once it has yielded its first chunk)."""
        if self._start_state is None:
            raise RvsmError("no start state yet: take the first chunk first")
        return self._start_state

    def state(self) -> np.ndarray:
        """The twin's state ``(S, H, W) int64`` after the last step :meth:`chunks` ran:
        the accumulators (the event sensor: the references). What the RTL's state
        memories hold at a frame boundary."""
        engine = self._engine_state
        if engine is None:
            raise RvsmError("no state yet: run chunks() first")
        if isinstance(engine, FusedFixedTwin):
            return np.asarray(engine.acc).astype(np.int64)
        return engine.integrator.state()


def open_stimulus_chunks(spec: dict | str) -> StimulusChunks:
    """A :class:`StimulusChunks` from its :attr:`~StimulusChunks.spec` (dict or JSON)."""
    from rvsm.model.scene.loaders import load_scene

    d = json.loads(spec) if isinstance(spec, str) else dict(spec)
    kind = d.get("kind")
    if kind == "stimulus":
        stim = open_stimulus(d["path"])
        steps = d.get("steps")
        if steps is not None and not 1 <= int(steps) <= stim.num_steps:
            raise RvsmError(f"{d['path']}: {steps} steps asked, the file holds "
                            f"{stim.num_steps}")
        if steps is not None and int(steps) < stim.num_steps:
            stim = stim.first_steps(int(steps))
        return StimulusChunks.from_stimulus(stim, d["path"], bool(d.get("recompute")))
    if kind == "scene":
        h, w = d["size"]
        scene = load_scene(d["scene"], size=(int(h), int(w)), num_frames=d["num_frames"],
                           steps_per_frame=d["steps_per_frame"], hold=d["hold"])
        point = parse_design_point(d["point"], "stimulus spec")
        return StimulusChunks.from_scene(scene, point, int(d["steps"]),
                                         d.get("engine", "fused"))
    raise RvsmError(f"not a stimulus description: {d!r}")
