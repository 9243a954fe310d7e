"""How a design point is built: the ``[rtl]`` table of its TOML, as :class:`BuildSettings`.

The table is not part of the contract: the twin ignores it; the :class:`DesignPoint` and
its text (which names it in sweeps) do not change with it. ``rvsm verilog``, ``rvsm
verify`` and ``rvsm fpga`` take each setting from it when their flag is not given
(docs/cli.md, "Build settings"). Here the table's keys and the types of their values are
checked (each key optional); whether a name is a registered architecture, interface,
memory, FPGA part or one of its packages is checked on the RTL side
(:func:`rvsm.rtl.fpga.build_settings.check_build_settings`), which this layer cannot
import.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from rvsm.model.infra.errors import RvsmError, shown

__all__ = ["BUILD_KEYS", "BUILD_SECTION", "BuildSettings", "build_settings_toml"]

#: The TOML section of the build settings.
BUILD_SECTION = "rtl"
#: Each key: (what it sets, with the flag it stands for; an example for `rvsm config new`).
BUILD_KEYS: dict[str, tuple[str, Any]] = {
    "arch": ("array architecture (--arch)", "stream"),
    "lanes": ("pixels per beat of the streaming array, divides the width (--lanes)", 40),
    "interface": ("native (the array's ports) | axis (the AXI IP) (--interface)", "native"),
    "freq_mhz": ("clock target, MHz (rvsm fpga --freq, rvsm verilog --clock-mhz)", 100.0),
    "device": ("FPGA part that rvsm fpga places (--device)", "ecp5-85"),
    "package": ("the device's package, judged by the I/O budget; rvsm fpga --board "
                "places it (--package)", "CABGA756"),
    "memory": ("state memories: dp16kd | inferred (rvsm fpga --memory)", "dp16kd"),
    "fifo_depth": ("output FIFO depth in beats, interface axis only (--fifo-depth)", 16),
}
_NAMES = ("arch", "interface", "device", "package", "memory")
_COUNTS = ("lanes", "fifo_depth")


@dataclass(frozen=True)
class BuildSettings:
    """The ``[rtl]`` table: every field ``None`` when the point does not set it.

    ``arch``, ``interface``, ``device``, ``package``, ``memory``: names (checked against
    the RTL's registries, ``package`` against the device's packages, by
    :func:`rvsm.rtl.fpga.build_settings.check_build_settings`); ``lanes``
    (pixels per beat) and ``fifo_depth`` (beats): integers >= 1; ``freq_mhz``: clock
    target in MHz, > 0.
    """

    arch: str | None = None
    lanes: int | None = None
    interface: str | None = None
    freq_mhz: float | None = None
    device: str | None = None
    package: str | None = None
    memory: str | None = None
    fifo_depth: int | None = None

    @classmethod
    def from_table(cls, table: object, source: str = "design point") -> BuildSettings:
        """From the TOML table ``[rtl]`` (``None``: no table); :class:`RvsmError` naming
        ``rtl.<key>`` for an unknown key or a value of the wrong type or range."""
        if table is None:
            return cls()
        if not isinstance(table, Mapping):
            raise RvsmError(f"{source}: [{BUILD_SECTION}] must be a table of "
                            f"{', '.join(BUILD_KEYS)}")
        values: dict[str, Any] = {}
        for key, value in table.items():
            where = f"{source}: {BUILD_SECTION}.{shown(key)}"
            if key not in BUILD_KEYS:
                raise RvsmError(f"{source}: unknown key {BUILD_SECTION}.{shown(key)}; "
                                f"[{BUILD_SECTION}] takes {', '.join(BUILD_KEYS)}")
            if key in _NAMES:
                if not isinstance(value, str) or not value:
                    raise RvsmError(f"{where} must be a name (a string), got {shown(value)}")
            elif key in _COUNTS:
                if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                    raise RvsmError(f"{where} must be an integer >= 1, got {shown(value)}")
            elif (isinstance(value, bool) or not isinstance(value, (int, float))
                  or not value > 0 or value == float("inf")):
                raise RvsmError(f"{where} must be a number of MHz > 0, got {shown(value)}")
            else:
                value = float(value)
            values[key] = value
        return cls(**values)

    def given(self) -> dict[str, Any]:
        """The keys the table sets, in :data:`BUILD_KEYS` order, with their values."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}


def build_settings_toml() -> str:
    """The ``[rtl]`` table commented out, one example value per key, for ``rvsm config
    new``: a point is built with today's defaults until a line is uncommented."""
    import tomli_w

    lines = ["", "# How the point is built (not part of the contract; the twin ignores it):",
             "# rvsm verilog, rvsm verify and rvsm fpga take each setting from here when",
             "# its flag is not given (docs/cli.md, \"Build settings\"). Uncomment to use.",
             f"# [{BUILD_SECTION}]"]
    for key, (what, example) in BUILD_KEYS.items():
        lines.append(f"# {key}: {what}")
        lines.append(f"# {tomli_w.dumps({key: example}).rstrip()}")
    return "\n".join(lines) + "\n"
