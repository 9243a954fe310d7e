"""Sweep files: parse, validate and expand a fixed-point design sweep (docs/design-space.md).

(The ``[run]`` and ``[hardware]`` tables are :mod:`.run_settings`, re-exported here.)

A sweep file (TOML) names a base design point (``[base]``), the axes to vary (``[axes]``,
keyed by the design point's ``section.key`` names), what to run (``[run]``: scenes, size,
frames, seeds, noise) and how to measure hardware (``[hardware]``). :func:`expand` turns it
into :class:`SweepTask` s, one per design point x scene x noise x seed, each with a stable
``point_id`` (SHA-256 of the canonical design point TOML, scene, steps, seed, noise and
size), so a rerun recognises what it has already computed.

Axis values: a list (``[6, 7, 8]``), an inclusive range (``{start = 6, stop = 12, step =
2}``), or for ``weights.bits`` / ``datapath.accumulator_bits`` the strings ``"auto"`` /
``"auto+N"`` (the smallest width that holds the quantised weights / the largest threshold,
plus N). Linked axes move together: ``"weights.bits,weights.frac_bits" = [[8, 6], [9, 7]]``.
A point the design point validation refuses is kept, as invalid, with the reason.
Top-level keys ``fits`` and ``camera`` (and optionally ``memory_organisation``,
``max_utilisation``) state a device constraint (:mod:`rvsm.sim.sweep.fit`) that the report
checks every design against.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from rvsm.model.fixed.design_point import (
    FIELDS,
    DesignPoint,
    default_design_point,
)
from rvsm.model.fixed.point_toml import (
    design_point_toml,
    from_toml_dict,
    load_design_point,
    to_toml_dict,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.fit import CONSTRAINT_KEYS, FitConstraint, parse_constraint
from rvsm.sim.sweep.run_settings import (
    HardwareSettings,
    RunSettings,
    parse_hardware,
    parse_run,
)

__all__ = ["AUTO_AXES", "AXES", "RUN_ONLY", "Design", "HardwareSettings", "RunSettings",
           "SweepSpec", "SweepTask", "load_sweep", "make_design", "parse_base_point",
           "parse_sweep", "task_id", "toml_tables"]

#: ``section.key`` -> design point field name of every field a sweep may vary.
AXES: dict[str, str] = {f.path: f.name for f in FIELDS if f.sweep}
#: Fields set by ``[run]`` (array size, noise, seed), not by axes.
RUN_ONLY: tuple[str, ...] = tuple(f.path for f in FIELDS if not f.sweep)
#: Axes that may say ``"auto"`` / ``"auto+N"`` (smallest width + N).
AUTO_AXES: tuple[str, ...] = tuple(f.path for f in FIELDS if f.auto)
SECTIONS = ("base", "axes", "run", "hardware")
MAX_POINTS = 100_000


@dataclass(frozen=True)
class Design:
    """One combination of axis values: the full design point (base array size, noise off)
    or, when validation refused it, ``point = None`` and ``error``."""

    design_id: str
    axes: dict[str, Any]
    point: DesignPoint | None
    error: str | None
    toml: str


@dataclass(frozen=True)
class SweepTask:
    """One design x scene x noise x seed: what a worker computes (one results row)."""

    point_id: str
    design: Design
    scene: str
    noise: bool
    seed: int
    steps: int
    size: tuple[int, int]

    @property
    def size_text(self) -> str:
        """``"HxW"``."""
        return f"{self.size[0]}x{self.size[1]}"

    def run_point(self) -> DesignPoint:
        """The design point as run: sweep size, this task's noise and seed."""
        assert self.design.point is not None
        return dataclasses.replace(
            self.design.point, height=self.size[0], width=self.size[1],
            noise=self.noise, seed=self.seed,
        )


@dataclass(frozen=True)
class SweepSpec:
    """A parsed, validated sweep file."""

    source: str
    text: str
    base: DesignPoint
    axes: tuple[tuple[tuple[str, ...], tuple[tuple[Any, ...], ...]], ...]
    run: RunSettings
    hardware: HardwareSettings
    designs: tuple[Design, ...] = field(default=(), repr=False)
    #: The device constraint (``fits``, ``camera``), or None.
    constraint: FitConstraint | None = None

    @property
    def sweep_hash(self) -> str:
        """Digest of the file text (16 hex digits)."""
        return hashlib.sha256(self.text.encode()).hexdigest()[:16]

    def tasks(self) -> list[SweepTask]:
        """Every design x scene x noise x seed, in a stable order."""
        out = []
        for d in self.designs:
            for scene, noise, seed in itertools.product(
                self.run.scenes, self.run.noise, self.run.seeds
            ):
                out.append(SweepTask(
                    point_id=task_id(d.toml, scene, self.run.steps, seed, noise, self.run.size),
                    design=d, scene=scene, noise=noise, seed=seed, steps=self.run.steps,
                    size=self.run.size,
                ))
        return out


def task_id(
    toml: str, scene: str, steps: int, seed: int, noise: bool, size: tuple[int, int]
) -> str:
    """Stable id of a results row: SHA-256 (24 hex digits) of the canonical point and run."""
    key = json.dumps([toml, scene, int(steps), int(seed), bool(noise), list(size)])
    return hashlib.sha256(key.encode()).hexdigest()[:24]


def load_sweep(path: str | os.PathLike) -> SweepSpec:
    """Read and validate a sweep file; errors name the file and the field."""
    from rvsm.model.infra.text_files import read_utf8_text

    p = Path(path)
    return parse_sweep(read_utf8_text(p, "sweep file"), str(p), base_dir=p.parent)


def parse_sweep(
    text: str, source: str = "sweep", base_dir: str | os.PathLike | None = None
) -> SweepSpec:
    """Parse sweep TOML text (``base_dir`` resolves a relative base file)."""
    data = toml_tables(text, source, SECTIONS, CONSTRAINT_KEYS)
    base = parse_base_point(data.get("base"), source, Path(base_dir or "."))
    axes = _parse_axes(data.get("axes", {}), source)
    run = parse_run(data.get("run"), source)
    hardware = parse_hardware(data.get("hardware", {}), source)
    constraint = parse_constraint(data, source)
    spec = SweepSpec(source, text, base, axes, run, hardware, constraint=constraint)
    return dataclasses.replace(spec, designs=tuple(_expand(spec)))


def toml_tables(text: str, source: str, sections: tuple[str, ...],
                keys: tuple[str, ...] = ()) -> dict[str, Any]:
    """TOML ``text`` parsed, refusing (one line naming ``source``) invalid TOML or a
    top-level table not in ``sections`` (or key not in ``keys``)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RvsmError(f"{source}: not valid TOML: {exc}") from None
    for key in data:
        if key not in sections and key not in keys:
            valid = ", ".join(sections) + (f"; top-level keys: {', '.join(keys)}" if keys else "")
            raise RvsmError(f"{source}: unknown section [{key}]; valid: {valid}")
    return data


def parse_base_point(raw: Any, source: str, base_dir: Path) -> DesignPoint:
    """A ``[base]`` table (or file name): the default point, a design point file, and
    per-section overrides; errors name ``source`` and the field."""
    if raw is None:
        return default_design_point()
    if isinstance(raw, str):
        raw = {"file": raw}
    if not isinstance(raw, dict):
        raise RvsmError(f"{source}: base must be a design point file name or a table")
    raw = dict(raw)
    file = raw.pop("file", None)
    if file is not None:
        if not isinstance(file, str):
            raise RvsmError(f"{source}: base.file must be a path string, got {file!r}")
        point = load_design_point(base_dir / file)
    else:
        point = default_design_point()
    if raw:
        merged = to_toml_dict(point)
        for sec, table in raw.items():
            if not isinstance(table, dict):
                raise RvsmError(f"{source}: base.{sec} must be a table like [base.{sec}]")
            merged.setdefault(sec, {}).update(table)
        point = from_toml_dict(merged, f"{source}: [base]")
    return point


def _parse_axes(raw: Any, source: str) -> tuple:
    if not isinstance(raw, dict):
        raise RvsmError(f"{source}: [axes] must be a table of \"section.key\" = values")
    axes = []
    seen: set[str] = set()
    for key, value in raw.items():
        if isinstance(value, dict) and "start" not in value and "values" not in value:
            raise RvsmError(
                f"{source}: axes.{key}: quote dotted axis names (\"adc.bits\" = [...]) so "
                "TOML does not read them as tables"
            )
        paths = tuple(p.strip() for p in str(key).split(","))
        for p in paths:
            where = f"{source}: axes.\"{key}\""
            if p in RUN_ONLY:
                raise RvsmError(
                    f"{where}: {p} is set by [run] (size, noise, seeds), not an axis"
                )
            if p not in AXES:
                valid = ", ".join(AXES)
                raise RvsmError(f"{where}: unknown field {p}; axes take {valid}")
            if p in seen:
                raise RvsmError(f"{where}: {p} is swept twice")
            seen.add(p)
        values = _axis_values(value, f"{source}: axes.\"{key}\"")
        combos = []
        for v in values:
            combo = tuple(v) if len(paths) > 1 else (v,)
            if len(paths) > 1 and (not isinstance(v, list) or len(v) != len(paths)):
                raise RvsmError(
                    f"{source}: axes.\"{key}\": each value must be a list of {len(paths)} "
                    f"values (one per linked field), got {v!r}"
                )
            for p, x in zip(paths, combo, strict=True):
                if isinstance(x, str) and x.startswith("auto"):
                    if p not in AUTO_AXES:
                        raise RvsmError(
                            f"{source}: axes.\"{key}\": {x!r} is only allowed for "
                            f"{' and '.join(AUTO_AXES)}"
                        )
                    _auto_offset(x, f"{source}: axes.\"{key}\"")
            combos.append(combo)
        axes.append((paths, tuple(combos)))
    return tuple(axes)


def _axis_values(value: Any, where: str) -> list:
    if isinstance(value, list):
        if not value:
            raise RvsmError(f"{where}: empty list of values")
        return value
    if isinstance(value, dict):
        extra = set(value) - {"start", "stop", "step"}
        if extra or "start" not in value or "stop" not in value:
            raise RvsmError(f"{where}: a range is {{start = A, stop = B, step = C}} (stop "
                            "included, step default 1)")
        start, stop, step = value["start"], value["stop"], value.get("step", 1)
        nums = (start, stop, step)
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in nums):
            raise RvsmError(f"{where}: start, stop and step must be numbers")
        if not all(math.isfinite(v) for v in nums):
            raise RvsmError(f"{where}: start, stop and step must be finite numbers")
        if step <= 0 or stop < start:
            raise RvsmError(f"{where}: need step > 0 and stop >= start, got {value}")
        count = (stop - start) / step + 1e-9
        if not math.isfinite(count) or count >= MAX_POINTS:
            raise RvsmError(f"{where}: range has more than {MAX_POINTS} values")
        n = int(math.floor(count)) + 1
        if n > MAX_POINTS:
            raise RvsmError(f"{where}: range has {n} values, more than {MAX_POINTS}")
        if all(isinstance(v, int) for v in nums):
            return [start + i * step for i in range(n)]
        return [round(start + i * step, 12) for i in range(n)]
    raise RvsmError(f"{where}: give a list of values or a range {{start, stop, step}}, "
                    f"not {value!r} (a single value belongs in [base])")


def _auto_offset(text: str, where: str) -> int:
    rest = text[4:].strip()
    if not rest:
        return 0
    try:
        if rest[0] not in "+-":
            raise ValueError
        return int(rest)
    except ValueError:
        raise RvsmError(f"{where}: {text!r} is not \"auto\" or \"auto+N\"") from None


def _expand(spec: SweepSpec) -> list[Design]:
    names = [paths for paths, _ in spec.axes]
    value_lists = [values for _, values in spec.axes]
    n = math.prod(len(v) for v in value_lists) if value_lists else 1
    if n > MAX_POINTS:
        raise RvsmError(f"{spec.source}: [axes] make {n} design points, more than {MAX_POINTS}")
    designs: dict[str, Design] = {}
    for combo in itertools.product(*value_lists):
        axes: dict[str, Any] = {}
        for paths, values in zip(names, combo, strict=True):
            axes.update(zip(paths, values, strict=True))
        d = make_design(spec.base, axes)
        designs.setdefault(d.design_id, d)
    return list(designs.values())


def make_design(base: DesignPoint, axes: dict[str, Any]) -> Design:
    """Apply ``axes`` (``section.key -> value``, ``"auto[+N]"`` allowed) to ``base``."""
    changes: dict[str, Any] = {"noise": False, "seed": 0}
    extra_bits: dict[str, int] = {}
    for path, value in axes.items():
        name = AXES[path]
        if isinstance(value, str) and path in AUTO_AXES and value.startswith("auto"):
            extra_bits[name] = _auto_offset(value, path)
        else:
            changes[name] = value
    try:
        point = DesignPoint.with_smallest_widths(base, changes, extra_bits)
    except RvsmError as exc:
        text = json.dumps({"base": base.to_dict(), "axes": axes}, sort_keys=True, default=str)
        return Design(hashlib.sha256(text.encode()).hexdigest()[:16], dict(axes), None,
                      str(exc), text)
    except (TypeError, ValueError) as exc:  # pragma: no cover - defensive
        text = json.dumps({"base": base.to_dict(), "axes": axes}, sort_keys=True, default=str)
        return Design(hashlib.sha256(text.encode()).hexdigest()[:16], dict(axes), None,
                      f"{type(exc).__name__}: {exc}", text)
    toml = design_point_toml(point)
    return Design(hashlib.sha256(toml.encode()).hexdigest()[:16], dict(axes), point, None, toml)
