"""Formal plans: a matrix of formal runs, ``rvsm formal --plan PLAN.toml`` (docs/formal.md).

A plan is TOML in the style of a regression plan (``regressions/formal-equivalence.toml``)::

    [regression]
    name = "equivalence"        # names the run folders and <name>-matrix.json

    [base]                      # the design point, as a regression plan's [base]
    file = "../tests/data/formal-tiny.toml"

    [formal]
    arch = "stream"             # a registered architecture with formal checks
    models = ["dog2", "dog4"]   # array.model values (default: every model)
    configs = [{ size = "3x4", lanes = 2 }]   # array sizes, each with the
                                # architecture's options
    resets = ["subtract", "zero"]   # threshold.reset modes (default: both)
    checks = ["equivalence"]    # the checks of every run (default: every check)
    timeout = 3600              # seconds per run before it counts as a tool failure

    [[override]]                # other checks for some runs (each key optional)
    models = ["dog4"]
    configs = [{ size = "3x4", lanes = 2 }]
    checks = ["window", "sums", "composed"]

Its runs are configs x models x resets (in that order), each a :class:`FormalRun`: the
base point with the model, at the size, in the reset mode, its contract built once, the
architecture's options and the checks (the last override naming the run wins).
:func:`load_formal_plan` refuses a bad plan in one line naming the field, before any
solver starts: an unknown model, check or option, a size the architecture cannot build.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.model.scene.loaders import parse_size
from rvsm.rtl.architectures.registry import ARCHITECTURES, DEFAULT_ARCHITECTURE
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.formal.runner import available_checks
from rvsm.sim.sweep.spec import parse_base_point, toml_tables

__all__ = ["FormalPlan", "FormalRun", "load_formal_plan", "parse_formal_plan"]

SECTIONS = ("regression", "base", "formal", "override")
FORMAL_KEYS = ("arch", "models", "configs", "resets", "checks", "timeout")
OVERRIDE_KEYS = ("models", "configs", "checks")
RESETS = ("subtract", "zero")


@dataclass(frozen=True)
class FormalRun:
    """One run of a plan: ``model``, ``size`` (H, W), the architecture's ``options``,
    ``reset``, the ``contract`` those make and the ``checks`` to run on it."""

    model: str
    size: tuple[int, int]
    options: dict[str, int]
    reset: str
    contract: ArrayContract
    checks: tuple[str, ...]

    def folder(self, plan: str) -> str:
        """The run's folder name: ``equivalence-dog2-3x4-lanes2-zero``."""
        opts = "".join(f"-{k}{v}" for k, v in self.options.items())
        return f"{plan}-{self.model}-{self.size[0]}x{self.size[1]}{opts}-{self.reset}"

    @property
    def label(self) -> str:
        """``dog2    3x4 lanes 2 zero    ``: how a progress line names it."""
        opts = " ".join(f"{k} {v}" for k, v in self.options.items())
        return (f"{self.model:7} {self.size[0]}x{self.size[1]}"
                + (f" {opts}" if opts else "") + f" {self.reset:8}")


@dataclass(frozen=True)
class FormalPlan:
    """A parsed plan: ``name``, ``source`` (path), the ``arch`` (a registry value), the
    ``timeout`` per run (None: none) and the ``runs``."""

    name: str
    source: str
    arch: Architecture
    timeout: float | None
    runs: tuple[FormalRun, ...]


def load_formal_plan(path: str | os.PathLike) -> FormalPlan:
    """Read and validate a plan file; errors name the file and the field."""
    from rvsm.model.infra.text_files import read_utf8_text

    p = Path(path)
    return parse_formal_plan(read_utf8_text(p, "formal plan"), str(p), base_dir=p.parent)


def _strings(raw: dict, key: str, default: tuple[str, ...], allowed: tuple[str, ...] | list[str],
             source: str, where: str) -> tuple[str, ...]:
    value = raw.get(key, list(default))
    value = value if isinstance(value, list) else [value]
    if not value:
        raise RvsmError(f"{source}: {where}.{key} must not be empty")
    for v in value:
        if v not in allowed:
            raise RvsmError(f"{source}: {where}.{key}: unknown {key[:-1]} {v!r}; choose "
                            f"from {', '.join(allowed)}")
    return tuple(value)


def _configs(raw: dict, arch: Architecture, source: str, where: str
             ) -> tuple[tuple[tuple[int, int], dict[str, int]], ...]:
    value = raw.get("configs")
    if not isinstance(value, list) or not value or not all(isinstance(c, dict)
                                                           for c in value):
        raise RvsmError(f"{source}: {where}.configs must be a list of tables "
                        "{ size = \"HxW\", <option> = N }")
    out = []
    for c in value:
        c = dict(c)
        try:
            size = parse_size(str(c.pop("size")))
            options = arch.resolve(c)
        except KeyError:
            raise RvsmError(f"{source}: {where}.configs: each needs size = \"HxW\"") from None
        except RvsmError as exc:
            raise RvsmError(f"{source}: {where}.configs: {exc}") from None
        out.append((size, options))
    return tuple(out)


def _keys(raw: Any, allowed: tuple[str, ...], source: str, where: str) -> dict:
    if not isinstance(raw, dict):
        raise RvsmError(f"{source}: [{where}] must be a table")
    unknown = [k for k in raw if k not in allowed]
    if unknown:
        raise RvsmError(f"{source}: unknown key {where}.{unknown[0]}; [{where}] takes "
                        f"{', '.join(allowed)}")
    return raw


def parse_formal_plan(text: str, source: str = "plan",
                      base_dir: str | os.PathLike | None = None) -> FormalPlan:
    """Parse plan TOML text (``base_dir`` resolves a relative ``[base] file``)."""
    data = toml_tables(text, source, SECTIONS)
    head = _keys(data.get("regression", {}), ("name",), source, "regression")
    name = head.get("name")
    if not isinstance(name, str) or not name.strip() or "/" in name:
        raise RvsmError(f"{source}: [regression] needs name = \"...\" (no slash)")
    base = parse_base_point(data.get("base"), source, Path(base_dir or "."))
    raw = _keys(data.get("formal"), FORMAL_KEYS, source, "formal")
    arch_name = raw.get("arch", DEFAULT_ARCHITECTURE)
    if arch_name not in ARCHITECTURES:
        raise RvsmError(f"{source}: formal.arch must be one of {', '.join(ARCHITECTURES)}, "
                        f"got {arch_name!r}")
    arch = ARCHITECTURES[arch_name]
    known = available_checks(arch)
    models = _strings(raw, "models", MODEL_NAMES, MODEL_NAMES, source, "formal")
    configs = _configs(raw, arch, source, "formal")
    resets = _strings(raw, "resets", RESETS, RESETS, source, "formal")
    checks = _strings(raw, "checks", tuple(known), known, source, "formal")
    timeout = raw.get("timeout")
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(
            timeout, int | float) or timeout <= 0):
        raise RvsmError(f"{source}: formal.timeout must be a number of seconds > 0")
    overrides = data.get("override", [])
    if not isinstance(overrides, list):
        raise RvsmError(f"{source}: override must be [[override]] tables")
    chosen: dict[tuple, tuple[str, ...]] = {}
    for o in overrides:
        o = _keys(o, OVERRIDE_KEYS, source, "override")
        o_checks = _strings(o, "checks", checks, known, source, "override")
        o_models = _strings(o, "models", models, models, source, "override")
        o_configs = _configs(o, arch, source, "override") if "configs" in o else configs
        if any(c not in configs for c in o_configs):
            raise RvsmError(f"{source}: override.configs: a config that is not in "
                            "formal.configs")
        for model in o_models:
            for size, options in o_configs:
                chosen[model, size, tuple(options.items())] = o_checks
    runs = []
    for size, options in configs:
        for model in models:
            contract = _contract(base, model, size, arch, options, source)
            for reset in resets:
                runs.append(FormalRun(model, size, options, reset,
                                      dataclasses.replace(contract, reset=reset),
                                      chosen.get((model, size, tuple(options.items())),
                                                 checks)))
    return FormalPlan(name, source, arch, None if timeout is None else float(timeout),
                      tuple(runs))


def _contract(base: Any, model: str, size: tuple[int, int], arch: Architecture,
              options: dict[str, int], source: str) -> ArrayContract:
    """The base point with ``model`` at ``size``, its contract checked by ``arch``."""
    if model != base.model and base.scale_phi is not None:
        raise RvsmError(f"{source}: models: the base point sets per-scale thresholds "
                        "(scale_phi) for its own model; remove them")
    try:
        point = base if model == base.model else dataclasses.replace(base, model=model)
        contract = point.with_size(*size).contract()
        arch.check(contract, **options)
    except (RvsmError, ValueError) as exc:
        raise RvsmError(f"{source}: model {model} at {size[0]}x{size[1]}: {exc}") from None
    return contract
