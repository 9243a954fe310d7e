"""Regression plans: what ``rvsm regress PLAN.toml`` runs (docs/regressions.md).

A plan is TOML with three tables::

    [regression]
    name = "smoke"                 # names the runs in the database and the JUnit file

    [base]                         # the design point, as a sweep's [base]: a file, or
    [base.array]                   # per-section overrides of the default point
    model = "dog4"

    [run]
    models = ["dog4", "dog2"]      # array.model values (default: the base's model)
    size = "16x16"                 # array size (H x W)
    arch = "stream"                # stream | parallel
    lanes = [2, 4]                 # lanes, for an architecture that takes them (stream)
    simulators = ["verilator"]     # icarus | verilator
    harness = "chunk"              # chunk (long-run harness) | cycle (per-cycle testbench);
                                   # default chunk where the architecture has a long run
    steps = 200                    # steps per run
    scenes = ["coin"]              # scene runs (optional)
    seeds = { start = 0, stop = 8 }  # random and corner stimuli (optional; or a list)
    protocol_seeds = [0, 1]        # protocol scripts: stalls, clears at any position,
                                   # colliding threshold writes (stream: an architecture
                                   # with protocol scripts; per cycle)
    code_coverage = false          # Verilator line and toggle coverage, merged (chunk)

Its runs are the product (scenes, then seeds, then protocol seeds) x models x lanes x
simulators, each with a key (a digest of everything that makes it) under which the
database keeps its result (:mod:`.store`). :func:`load_plan` refuses a bad plan in one
line naming the field.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.point_toml import design_point_toml
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.model.scene.loaders import is_builtin, parse_size
from rvsm.rtl.architectures.registry import ARCHITECTURES, DEFAULT_ARCHITECTURE, architectures_with
from rvsm.sim.cosim.builds.cocotb_adapter import SIMULATORS
from rvsm.sim.cosim.verify import HARNESSES
from rvsm.sim.sweep.spec import parse_base_point, toml_tables

__all__ = ["RegressionPlan", "RunSpec", "load_plan", "parse_plan"]

SECTIONS = ("regression", "base", "run")
RUN_KEYS = ("models", "size", "arch", "lanes", "simulators", "harness", "steps", "scenes",
            "seeds", "protocol_seeds", "code_coverage")


@dataclass(frozen=True)
class RunSpec:
    """One run of a plan: a ``scene`` name, a random ``seed`` or a protocol seed, the
    design point (TOML text, sized), architecture, lanes, simulator, harness and steps."""

    plan: str
    stimulus: str  # "scene:<name>", "seed:<n>" or "protocol:<n>"
    model: str
    point_toml: str
    size: tuple[int, int]
    arch: str
    lanes: int | None
    sim: str
    harness: str
    steps: int
    code_coverage: bool = False

    @property
    def key(self) -> str:
        """Digest of everything that makes this run (16 hex digits)."""
        text = json.dumps(dataclasses.asdict(self), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    @property
    def label(self) -> str:
        """A readable name: ``seed:3 dog4 16x16 stream P=4 verilator``."""
        lanes = f" P={self.lanes}" if self.lanes else ""
        return (f"{self.stimulus} {self.model} {self.size[0]}x{self.size[1]} "
                f"{self.arch}{lanes} {self.sim}")


@dataclass(frozen=True)
class RegressionPlan:
    """A parsed plan: its ``name``, ``source`` (path) and ``runs``."""

    name: str
    source: str
    runs: tuple[RunSpec, ...]


def load_plan(path: str | os.PathLike) -> RegressionPlan:
    """Read and validate a plan file; errors name the file and the field."""
    from rvsm.model.infra.text_files import read_utf8_text

    p = Path(path)
    return parse_plan(read_utf8_text(p, "regression plan"), str(p), base_dir=p.parent)


def _list(raw: dict, key: str, default: Any, source: str) -> list:
    value = raw.get(key, default)
    value = value if isinstance(value, list) else [value]
    if not value:
        raise RvsmError(f"{source}: run.{key} must not be empty")
    return value


def _seeds(raw: Any, source: str, key: str = "seeds") -> list[int]:
    if raw is None:
        return []
    if isinstance(raw, dict):
        if set(raw) - {"start", "stop"} or not all(
                isinstance(raw.get(k), int) and not isinstance(raw.get(k), bool)
                for k in ("start", "stop")):
            raise RvsmError(f"{source}: run.{key} must be a list of integers or "
                            "{ start = A, stop = B }")
        raw = list(range(raw["start"], raw["stop"]))
    raw = raw if isinstance(raw, list) else [raw]
    for s in raw:
        if isinstance(s, bool) or not isinstance(s, int) or s < 0:
            raise RvsmError(f"{source}: run.{key} must be integers >= 0, got {s!r}")
    return raw


def parse_plan(text: str, source: str = "plan",
               base_dir: str | os.PathLike | None = None) -> RegressionPlan:
    """Parse plan TOML text (``base_dir`` resolves a relative ``[base] file``)."""
    data = toml_tables(text, source, SECTIONS)
    head = data.get("regression", {})
    name = head.get("name") if isinstance(head, dict) else None
    if not isinstance(name, str) or not name.strip():
        raise RvsmError(f"{source}: [regression] needs name = \"...\"")
    if set(head) - {"name"}:
        raise RvsmError(f"{source}: unknown key regression.{sorted(set(head) - {'name'})[0]}")
    base = parse_base_point(data.get("base"), source, Path(base_dir or "."))
    raw = data.get("run")
    if not isinstance(raw, dict):
        raise RvsmError(f"{source}: missing [run] table")
    unknown = [k for k in raw if k not in RUN_KEYS]
    if unknown:
        raise RvsmError(f"{source}: unknown key run.{unknown[0]}; [run] takes "
                        f"{', '.join(RUN_KEYS)}")
    models = _list(raw, "models", base.model, source)
    for m in models:
        if m not in MODEL_NAMES:
            raise RvsmError(f"{source}: run.models: unknown model {m!r}; choose from "
                            f"{', '.join(MODEL_NAMES)}")
    try:
        size = parse_size(str(raw.get("size", f"{base.height}x{base.width}")))
    except RvsmError as exc:
        raise RvsmError(f"{source}: run.size: {exc}") from None
    arch = raw.get("arch", DEFAULT_ARCHITECTURE)
    if arch not in ARCHITECTURES:
        raise RvsmError(f"{source}: run.arch must be one of {', '.join(ARCHITECTURES)}, "
                        f"got {arch!r}")
    a = ARCHITECTURES[arch]
    lanes = _list(raw, "lanes", 1, source) if a.takes("lanes") else [None]
    for p in lanes:
        if p is not None and (isinstance(p, bool) or not isinstance(p, int) or p < 1
                              or size[1] % p):
            raise RvsmError(f"{source}: run.lanes: {p!r} must be an integer >= 1 dividing "
                            f"the width {size[1]}")
    sims = _list(raw, "simulators", "icarus", source)
    for s in sims:
        if s not in SIMULATORS:
            raise RvsmError(f"{source}: run.simulators: {s!r} is not one of "
                            f"{', '.join(SIMULATORS)}")
    long_run = a.long_run_testbench is not None
    harness = raw.get("harness", "chunk" if long_run else "cycle")
    if harness not in HARNESSES or (harness == "chunk" and not long_run):
        names = ", ".join(architectures_with(lambda x: x.long_run_testbench))
        raise RvsmError(f"{source}: run.harness must be one of {', '.join(HARNESSES)} "
                        f"(chunk for the {names} architecture only), got {harness!r}")
    steps = raw.get("steps", 100)
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise RvsmError(f"{source}: run.steps must be an integer >= 1, got {steps!r}")
    scenes = raw.get("scenes", [])
    scenes = scenes if isinstance(scenes, list) else [scenes]
    for sc in scenes:
        if not isinstance(sc, str) or not is_builtin(sc):
            raise RvsmError(f"{source}: run.scenes: {sc!r} is not a built-in scene name")
    seeds = _seeds(raw.get("seeds"), source)
    code_coverage = raw.get("code_coverage", False)
    if not isinstance(code_coverage, bool):
        raise RvsmError(f"{source}: run.code_coverage must be true or false")
    if code_coverage and (harness != "chunk" or set(sims) != {"verilator"}):
        raise RvsmError(f"{source}: run.code_coverage needs harness = \"chunk\" and "
                        "simulators = [\"verilator\"]")
    protocol = _seeds(raw.get("protocol_seeds"), source, "protocol_seeds")
    if protocol and a.protocol is None:
        names = ", ".join(architectures_with(lambda x: x.protocol))
        raise RvsmError(f"{source}: run.protocol_seeds drive the {names} architecture only")
    if not scenes and not seeds and not protocol:
        raise RvsmError(f"{source}: [run] needs scenes, seeds or protocol_seeds")
    runs = []
    stimuli = [f"scene:{s}" for s in scenes] + [f"seed:{n}" for n in seeds]
    stimuli += [f"protocol:{n}" for n in protocol]
    for stimulus in stimuli:
        per_cycle = stimulus.startswith("protocol:")  # its own per-cycle testbench
        for model in models:
            point = _point(base, model, size, source)
            for p in lanes:
                for sim in sims:
                    runs.append(RunSpec(name, stimulus, model, design_point_toml(point),
                                        size, arch, p, sim,
                                        "cycle" if per_cycle else harness, steps,
                                        code_coverage and not per_cycle))
    return RegressionPlan(name, source, tuple(runs))


def _point(base: DesignPoint, model: str, size: tuple[int, int], source: str) -> DesignPoint:
    try:
        point = dataclasses.replace(base, model=model) if model != base.model else base
        return point.with_size(*size)
    except (RvsmError, ValueError) as exc:
        raise RvsmError(f"{source}: model {model} at {size[0]}x{size[1]}: {exc}") from None
