"""The design point of one run: parsed once, its contract built once.

A command reads its design point TOML at its edge (:meth:`RunPoint.load`), sized by
``--size``, and passes the :class:`RunPoint` down: the co-simulation, the protocol runs
and the regressions take the point and its :class:`~rvsm.model.fixed.contract.ArrayContract`
from it instead of reading the file again or rebuilding the contract at each step.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint

__all__ = ["RunPoint"]


@dataclass(frozen=True)
class RunPoint:
    """A design ``point``, its ``contract`` (built from it once) and ``source``, where it
    came from (the TOML path results name, ``str(path)``)."""

    point: DesignPoint
    contract: ArrayContract
    source: str

    @classmethod
    def of(cls, point: DesignPoint, source: str | os.PathLike) -> RunPoint:
        """``point`` with its contract (built here, once)."""
        return cls(point, point.contract(), str(source))

    @classmethod
    def load(cls, path: str | os.PathLike, size: tuple[int, int] | None = None) -> RunPoint:
        """Parse the design point TOML at ``path`` (errors name the file and the field),
        resized to ``size = (H, W)`` when given."""
        from rvsm.model.fixed.point_toml import load_design_point

        point = load_design_point(path)
        return cls.of(point if size is None else point.with_size(*size), path)

    @classmethod
    def coerce(cls, point: RunPoint | str | os.PathLike,
               size: tuple[int, int] | None = None) -> RunPoint:
        """``point`` as it is (resized when ``size`` differs from its shape), or the TOML
        file it names loaded (:meth:`load`): library callers may pass either."""
        if not isinstance(point, RunPoint):
            return cls.load(point, size)
        if size is None or tuple(size) == point.shape:
            return point
        return cls.of(point.point.with_size(*size), point.source)

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` pixels."""
        return (self.point.height, self.point.width)
