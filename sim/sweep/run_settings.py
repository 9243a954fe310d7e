"""The ``[run]`` and ``[hardware]`` tables of a sweep file (:mod:`rvsm.sim.sweep.spec`):
what every design point of a sweep is run on (:class:`RunSettings`) and how its hardware
is measured (:class:`HardwareSettings`), each parsed with its refusals."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rvsm.model.decode.reconstruction import MATCH_MODES, METHODS
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import parse_size

__all__ = ["HARDWARE_KEYS", "MAX_HARDWARE_PIXELS", "RUN_KEYS", "HardwareSettings",
           "RunSettings", "parse_hardware", "parse_run", "positive_int"]


RUN_KEYS = ("scenes", "size", "frames", "steps_per_frame", "seeds", "noise", "method", "match")


HARDWARE_KEYS = ("enabled", "size", "lanes", "fmax")


#: Largest array ``[hardware] size`` may synthesise (pixels).
MAX_HARDWARE_PIXELS = 64 * 64


@dataclass(frozen=True)
class RunSettings:
    """``[run]``: scenes (built-in names or paths), twin size ``(H, W)`` pixels, frames,
    steps per frame, seeds, noise settings, reconstruction method and matching."""

    scenes: tuple[str, ...]
    size: tuple[int, int] = (64, 96)
    frames: int = 11
    steps_per_frame: int = 10
    seeds: tuple[int, ...] = (0,)
    noise: tuple[bool, ...] = (False,)
    method: str = "auto"
    match: str = "gain"

    @property
    def steps(self) -> int:
        """Simulated steps: ``(frames - 1) * steps_per_frame`` (``frames >= 2``)."""
        return (self.frames - 1) * self.steps_per_frame


@dataclass(frozen=True)
class HardwareSettings:
    """``[hardware]``: the streaming array of each distinct contract, synthesised at
    ``size`` (pixels) for two lane counts ``lanes`` (logic per lane = the slope), and, with
    ``fmax``, placed and routed at the first (minutes per design);
    :func:`rvsm.rtl.fpga.lane_cost.lane_cost`."""

    enabled: bool = True
    size: tuple[int, int] = (16, 16)
    lanes: tuple[int, int] = (1, 2)
    fmax: bool = False


def parse_run(raw: Any, source: str) -> RunSettings:
    if not isinstance(raw, dict):
        raise RvsmError(f"{source}: missing [run] table (run.scenes is required)")
    for key in raw:
        if key not in RUN_KEYS:
            raise RvsmError(f"{source}: unknown key run.{key}; [run] takes {', '.join(RUN_KEYS)}")
    scenes = raw.get("scenes")
    if isinstance(scenes, str):
        scenes = [scenes]
    if not isinstance(scenes, list) or not scenes or not all(isinstance(s, str) for s in scenes):
        raise RvsmError(f"{source}: run.scenes must be a non-empty list of scene names or "
                        "paths, e.g. [\"coin\", \"flyball\"]")
    size_text = raw.get("size", "64x96")
    try:
        size = parse_size(str(size_text))
    except RvsmError as exc:
        raise RvsmError(f"{source}: run.size: {exc}") from None
    frames = positive_int(raw.get("frames", 11), f"{source}: run.frames")
    if frames < 2:
        raise RvsmError(f"{source}: run.frames must be >= 2 (steps interpolate between "
                        f"frames), got {frames}")
    spf = positive_int(raw.get("steps_per_frame", 10), f"{source}: run.steps_per_frame")
    seeds = raw.get("seeds", [0])
    seeds = seeds if isinstance(seeds, list) else [seeds]
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, int) or s < 0:
            raise RvsmError(f"{source}: run.seeds must be integers >= 0, got {s!r}")
    noise = raw.get("noise", [False])
    noise = noise if isinstance(noise, list) else [noise]
    if not noise or not all(isinstance(n, bool) for n in noise):
        raise RvsmError(f"{source}: run.noise must be true, false or a list of them")
    method = raw.get("method", "auto")
    if method not in METHODS:
        raise RvsmError(f"{source}: run.method must be {_alternatives(METHODS)}, "
                        f"got {method!r}")
    match = raw.get("match", "gain")
    if match not in MATCH_MODES:
        raise RvsmError(f"{source}: run.match must be {_alternatives(MATCH_MODES)}, "
                        f"got {match!r}")
    return RunSettings(tuple(dict.fromkeys(scenes)), size, frames, spf,
                       tuple(dict.fromkeys(seeds)), tuple(dict.fromkeys(noise)), method, match)


def _alternatives(words: tuple[str, ...]) -> str:
    """``("a", "b", "c")`` -> ``"a, b or c"``."""
    return f"{', '.join(words[:-1])} or {words[-1]}"


def parse_hardware(raw: Any, source: str) -> HardwareSettings:
    if not isinstance(raw, dict):
        raise RvsmError(f"{source}: [hardware] must be a table")
    for key in raw:
        if key not in HARDWARE_KEYS:
            raise RvsmError(f"{source}: unknown key hardware.{key}; [hardware] takes "
                            f"{', '.join(HARDWARE_KEYS)}")
    enabled = raw.get("enabled", True)
    if not isinstance(enabled, bool):
        raise RvsmError(f"{source}: hardware.enabled must be true or false")
    try:
        size = parse_size(str(raw.get("size", "16x16")))
    except RvsmError as exc:
        raise RvsmError(f"{source}: hardware.size: {exc}") from None
    if size[0] * size[1] > MAX_HARDWARE_PIXELS:
        raise RvsmError(f"{source}: hardware.size {size[0]}x{size[1]} is larger than needed "
                        f"for logic per lane; use at most {MAX_HARDWARE_PIXELS} pixels, e.g. "
                        "\"16x16\"")
    lanes = raw.get("lanes", [1, 2])
    if not isinstance(lanes, list) or len(lanes) != 2 or any(
            isinstance(v, bool) or not isinstance(v, int) for v in lanes) \
            or not 1 <= lanes[0] < lanes[1]:
        raise RvsmError(f"{source}: hardware.lanes must be two lane counts [P1, P2] with "
                        f"1 <= P1 < P2, got {lanes!r}")
    if size[1] % lanes[0] or size[1] % lanes[1]:
        raise RvsmError(f"{source}: hardware.size width {size[1]} must be a multiple of "
                        f"both hardware.lanes {lanes}")
    fmax = raw.get("fmax", False)
    if not isinstance(fmax, bool):
        raise RvsmError(f"{source}: hardware.fmax must be true or false")
    return HardwareSettings(enabled, size, (lanes[0], lanes[1]), fmax)


def positive_int(v: Any, where: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise RvsmError(f"{where} must be an integer >= 1, got {v!r}")
    return v
