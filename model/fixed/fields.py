"""How a design-point field is declared: TOML place, valid values, comment, sweep role.

Each field of :class:`~rvsm.model.fixed.design_point.DesignPoint` is declared once, on
the class, with :func:`declare`::

    adc_bits: int = declare("adc", "bits", Integer(1, 16), 7, "ADC resolution N")

From those declarations come the TOML layout and its comments
(:mod:`rvsm.model.fixed.point_toml`, ``rvsm config new``), the validation (each
field's :class:`Kind` refuses a bad value naming ``section.key`` and the valid range)
and the sweep's axis names (:mod:`rvsm.sim.sweep.spec`). Checks that involve several
fields (scale count, weight overflow, threshold range) live on the design point.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from rvsm.model.infra.errors import RvsmError

__all__ = [
    "Choice", "Field", "Flag", "Integer", "Kind", "Number", "OptionalChoice",
    "PositiveNumbers", "declare", "fields_of",
]

_META = "rvsm.field"


class Kind(Protocol):
    """A field's valid values: ``check`` normalises or raises, ``describe`` documents."""

    def check(self, path: str, value: Any) -> Any:
        """The normalised value, or :class:`RvsmError` naming ``path`` and the range."""
        ...

    def describe(self) -> str:
        """The valid values in a few words (for comments and docs)."""
        ...


@dataclass(frozen=True)
class Integer:
    """An integer in ``lo..hi`` (bools refused)."""

    lo: int
    hi: int

    def check(self, path: str, value: Any) -> int:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
                or not self.lo <= value <= self.hi:
            raise RvsmError(f"{path} must be an integer in {self.lo}..{self.hi}, got {value!r}")
        return int(value)

    def describe(self) -> str:
        return f"integer {self.lo}..{self.hi}"


@dataclass(frozen=True)
class Number:
    """A finite number ``> 0`` (or ``>= 0`` with ``allow_zero``) and ``<= hi``, stored as
    float."""

    allow_zero: bool = False
    hi: float = math.inf

    def check(self, path: str, value: Any) -> float:
        ok = not isinstance(value, bool) and isinstance(value, (int, float, np.number)) \
            and math.isfinite(value)
        if not ok or value < 0 or (value == 0 and not self.allow_zero):
            rel = ">= 0" if self.allow_zero else "> 0"
            raise RvsmError(f"{path} must be a finite number {rel}, got {value!r}")
        if value > self.hi:
            raise RvsmError(f"{path} must be <= {self.hi:g}, got {value!r}")
        return float(value)

    def describe(self) -> str:
        text = "number >= 0" if self.allow_zero else "number > 0"
        return text if self.hi == math.inf else f"{text}, <= {self.hi:g}"


@dataclass(frozen=True)
class Choice:
    """One of ``choices``; with ``normalise``, compared after ``strip().lower()``."""

    choices: tuple[str, ...]
    normalise: bool = False
    noun: str = ""

    def check(self, path: str, value: Any) -> str:
        v = value.strip().lower() if self.normalise and isinstance(value, str) else value
        if v not in self.choices:
            if self.noun:
                raise RvsmError(f"{path} = {value!r} is not a {self.noun}; "
                                f"choose one of: {', '.join(self.choices)}")
            raise RvsmError(f"{path} must be one of {', '.join(self.choices)}; got {value!r}")
        return v

    def describe(self) -> str:
        return " | ".join(self.choices)


@dataclass(frozen=True)
class OptionalChoice:
    """``None`` (not set: the field's documented default applies) or one of ``choices``."""

    choices: tuple[str, ...]

    def check(self, path: str, value: Any) -> str | None:
        return None if value is None else Choice(self.choices).check(path, value)

    def describe(self) -> str:
        return "optional: " + " | ".join(self.choices)


@dataclass(frozen=True)
class Flag:
    """``true`` or ``false``."""

    def check(self, path: str, value: Any) -> bool:
        if not isinstance(value, (bool, np.bool_)):
            raise RvsmError(f"{path} must be true or false, got {value!r}")
        return bool(value)

    def describe(self) -> str:
        return "true | false"


@dataclass(frozen=True)
class PositiveNumbers:
    """Optional list of finite numbers ``> 0`` (``None`` = not set), stored as a tuple."""

    def check(self, path: str, value: Any) -> tuple[float, ...] | None:
        if value is None:
            return None
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
            raise RvsmError(f"{path} must be a list of numbers")
        for v in value:
            if isinstance(v, bool) or not isinstance(v, (int, float, np.number)) \
                    or not math.isfinite(v) or v <= 0:
                raise RvsmError(f"{path} must hold finite numbers > 0, got {v!r}")
        return tuple(float(v) for v in value)

    def describe(self) -> str:
        return "optional list of numbers > 0"


@dataclass(frozen=True)
class Field:
    """One declared field: attribute ``name``, TOML ``section``/``key``, ``kind`` (valid
    values), ``default``, ``doc`` (one line), whether a sweep may vary it (``sweep``)
    and whether a sweep may ask for its smallest width (``auto``)."""

    section: str
    key: str
    kind: Kind
    doc: str
    sweep: bool = True
    auto: bool = False
    name: str = ""
    default: Any = None

    @property
    def path(self) -> str:
        """``section.key``, the name errors, sweeps and docs use."""
        return f"{self.section}.{self.key}"

    def comment(self) -> str:
        """``doc (valid values)``: the comment above the key in ``rvsm config new``."""
        return f"{self.doc} ({self.kind.describe()})"


def declare(section: str, key: str, kind: Kind, default: Any, doc: str, *,
            sweep: bool = True, auto: bool = False) -> Any:
    """A dataclass field with its :class:`Field` declaration as metadata."""
    spec = Field(section, key, kind, doc, sweep, auto)
    return dataclasses.field(default=default, metadata={_META: spec})


def fields_of(cls: type) -> tuple[Field, ...]:
    """The declared fields of dataclass ``cls``, in declaration (= TOML file) order."""
    return tuple(
        dataclasses.replace(f.metadata[_META], name=f.name, default=f.default)
        for f in dataclasses.fields(cls) if _META in f.metadata
    )
