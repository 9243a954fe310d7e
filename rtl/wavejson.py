"""Timing diagrams from a simulation: a table of per-cycle values as WaveDrom WaveJSON.

A :class:`CycleTable` is filled by a test bench, one row per clock period: period ``j``
lies between rising edges ``j - 1`` and ``j`` and holds the inputs sampled at edge ``j``
and the outputs presented after edge ``j - 1`` (what a waveform viewer shows between the
two edges). Each column is a one-bit wire (``bool``) or a bus (a ``str`` label, ``None``
for "don't care", drawn as ``x``). :meth:`CycleTable.wavejson` turns a window of periods
into WaveJSON (https://wavedrom.com/tutorial.html), which ``wavedrom`` renders to SVG.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

__all__ = ["CycleTable"]


@dataclass
class CycleTable:
    """Per-period values of named wires and buses, in the order first recorded.

    Members: ``columns`` (name -> list of values, one per period), ``kinds`` (name ->
    ``"bit"`` or ``"bus"``).
    """

    columns: dict[str, list[bool | str | None]] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)

    @property
    def num_periods(self) -> int:
        """Periods recorded."""
        return max((len(v) for v in self.columns.values()), default=0)

    def record(self, values: Mapping[str, bool | int | str | None]) -> None:
        """Append one period: ``bool``/``int`` values are wires (``0``/``1``), ``str``
        and ``None`` bus labels; every column must be given in every period."""
        n = self.num_periods
        if self.columns and set(values) != set(self.columns):
            raise ValueError(f"period {n}: columns {sorted(values)} differ from "
                             f"{sorted(self.columns)}")
        for name, v in values.items():
            kind = "bus" if v is None or isinstance(v, str) else "bit"
            if name not in self.columns:
                self.columns[name], self.kinds[name] = [], kind
            elif kind == "bit" and self.kinds[name] == "bus":
                raise ValueError(f"column {name!r} is a bus: give a label or None")
            self.columns[name].append(bool(v) if kind == "bit" else v)

    def wavejson(self, title: str, start: int = 0, stop: int | None = None,
                 foot: str = "", groups: Mapping[str, tuple[str, ...]] | None = None,
                 ) -> dict:
        """WaveJSON of periods ``start .. stop - 1`` with a ``clk`` row first.

        ``groups`` (label -> column names) draws columns in labelled groups, in that
        order; without it every column is drawn in recording order. The head's tock
        numbers each period by its index in the table, so a diagram's numbers are the
        simulation's periods.
        """
        stop = self.num_periods if stop is None else stop
        if not 0 <= start < stop <= self.num_periods:
            raise ValueError(f"window {start}..{stop} outside 0..{self.num_periods}")
        n = stop - start
        rows: list = [{"name": "clk", "wave": "p" + "." * (n - 1)}]
        order = groups or {"": tuple(self.columns)}
        for label, names in order.items():
            lanes = [self._lane(name, start, stop) for name in names]
            rows.append([label, *lanes] if label else lanes)
        if not groups:
            rows = [rows[0], *rows[1]]
        head = {"text": title, "tock": start}
        out: dict = {"signal": rows, "head": head}
        if foot:
            out["foot"] = {"text": foot}
        return out

    def _lane(self, name: str, start: int, stop: int) -> dict:
        if name not in self.columns:
            raise KeyError(f"no column {name!r}")
        values = self.columns[name][start:stop]
        wave, data = [], []
        previous: object = object()
        for v in values:
            if self.kinds[name] == "bit":
                wave.append("." if v == previous else ("1" if v else "0"))
            elif v is None:
                wave.append("." if previous is None else "x")
            else:
                wave.append("." if v == previous else "=")
                if v != previous:
                    data.append(v)
            previous = v
        lane: dict = {"name": name, "wave": "".join(wave)}
        if data:
            lane["data"] = data
        return lane
