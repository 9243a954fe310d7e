"""How ``rvsm verilog``, ``rvsm verify`` and ``rvsm fpga`` choose what they build: each
setting from its flag, else from the design point's ``[rtl]`` table, else today's default.

:func:`choose_build` reads the point's table (checked against the registries by
:func:`~rvsm.rtl.fpga.build_settings.check_build_settings`), fills the flags not given
into the ``argparse`` namespace (so the commands read ``args`` as before), says once on
stderr which settings came from the point, and returns a :class:`BuildChoice` whose
:meth:`~BuildChoice.record` is what ``--json`` reports as ``settings``. An option of the
point (``lanes``, ``fifo_depth``) that the architecture chosen on the command line does
not take is not used, and the line says so.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, NATIVE, get_architecture

__all__ = ["ARCH_DEFAULTS", "FLAGS", "BuildChoice", "choose_build"]

#: Setting -> (its flag, how the stderr line shows a value).
FLAGS: dict[str, tuple[str, str]] = {
    "arch": ("--arch", "arch {}"),
    "interface": ("--interface", "interface {}"),
    "lanes": ("--lanes", "lanes {}"),
    "fifo_depth": ("--fifo-depth", "FIFO depth {}"),
    "freq_mhz": ("--freq", "freq {:g} MHz"),
    "device": ("--device", "device {}"),
    "package": ("--package", "package {}"),
    "memory": ("--memory", "memory {}"),
}
#: The settings that are architecture options (their defaults are the architecture's).
_OPTIONS = ("lanes", "fifo_depth")
#: Today's defaults of the settings every RTL command has.
ARCH_DEFAULTS: dict[str, tuple[str, Any]] = {
    "arch": ("arch", DEFAULT_ARCHITECTURE), "interface": ("interface", NATIVE),
    "lanes": ("lanes", None), "fifo_depth": ("fifo_depth", None)}


@dataclass(frozen=True)
class BuildChoice:
    """What a command builds: ``values`` (setting -> value, options not yet resolved),
    the settings taken ``from_point`` and those of the point ``unused``, and the point
    file (``None``: no point file)."""

    values: dict[str, Any]
    from_point: tuple[str, ...]
    unused: tuple[str, ...]
    point: str | None

    def record(self, options: dict[str, int]) -> dict[str, Any]:
        """The effective settings for ``--json``: ``values`` with the architecture's
        resolved ``options`` (defaults filled in), ``from_point`` and ``point``."""
        out = {k: v for k, v in self.values.items() if k not in _OPTIONS}
        out.update({k: options.get(k) for k in _OPTIONS if k in self.values})
        return {**out, "from_point": list(self.from_point), "point": self.point}


def choose_build(args: argparse.Namespace, command: str, point: str | None,
                 dests: dict[str, tuple[str, Any]]) -> BuildChoice:
    """Fill ``args`` from the point file ``point`` where a flag was not given.

    ``dests``: the command's settings, setting -> (the ``args`` attribute, its default;
    ``None`` for an architecture option, whose default is the architecture's). The
    point's ``[rtl]`` table is checked first (:class:`RvsmError`, exit 2).
    """
    from rvsm.model.fixed.build_settings import BuildSettings

    settings = BuildSettings()
    if point is not None:
        from rvsm.model.fixed.point_toml import load_point_file
        from rvsm.rtl.fpga.build_settings import check_build_settings

        settings = load_point_file(point)[1]
        check_build_settings(settings, point)
    given = settings.given()
    taken: list[str] = []
    order = sorted(dests, key=lambda k: k in _OPTIONS)  # arch, interface before options
    for key in order:
        dest, default = dests[key]
        if key in _OPTIONS or getattr(args, dest) is not None:
            continue
        if key in given:
            setattr(args, dest, given[key])
            taken.append(key)
        else:
            setattr(args, dest, default)
    unused: list[str] = []
    options = [k for k in order if k in _OPTIONS]
    if options:
        try:
            built = get_architecture(args.arch, getattr(args, "interface", NATIVE))
        except RvsmError:
            built = None  # the command refuses the combination in its own words
        for key in options:
            dest, _ = dests[key]
            if getattr(args, dest) is not None or key not in given:
                continue
            if built is None:
                continue  # refused by the command next: nothing to say about options
            if built.takes(key):
                setattr(args, dest, given[key])
                taken.append(key)
            else:
                unused.append(key)
    _say(command, point, dests, given, taken, unused, args)
    values = {k: getattr(args, dests[k][0]) for k in dests}
    return BuildChoice(values, tuple(k for k in FLAGS if k in taken),
                       tuple(unused), point)


def _say(command: str, point: str | None, dests: dict[str, tuple[str, Any]],
         given: dict[str, Any], taken: list[str], unused: list[str],
         args: argparse.Namespace) -> None:
    """The one stderr line: the settings taken from the point, those not used."""
    if not taken and not unused:
        return
    parts = []
    if taken:
        shown = ", ".join(FLAGS[k][1].format(getattr(args, dests[k][0]))
                          for k in FLAGS if k in taken)
        parts.append(f"{shown} from {point} [rtl]")
    if unused:
        arch = getattr(args, "arch", None)
        interface = getattr(args, "interface", NATIVE)
        parts.append(", ".join(f"rtl.{k} not used" for k in unused)
                     + f" (arch {arch}, interface {interface} does not take it)")
    print(f"rvsm {command}: " + "; ".join(parts), file=sys.stderr, flush=True)
