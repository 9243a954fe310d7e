"""A design point's ``[rtl]`` table checked against what the RTL offers.

:class:`~rvsm.model.fixed.build_settings.BuildSettings` (the model layer) checks keys and
types; here each name is checked against its registry: ``arch`` an ``--arch`` choice
(:data:`~rvsm.rtl.architectures.registry.ARCHITECTURES`), ``interface`` one registered
for that architecture, ``device`` one of the one device list
(:func:`~rvsm.rtl.fpga.devices.device_names`: the parts ``rvsm fpga`` places and the
estimate-only ones, which ``rvsm fpga`` refuses in one line), ``package`` one of that
device's packages (:func:`device_packages`; default device ``ecp5-85``), ``memory`` one of
:data:`~rvsm.rtl.fpga.flow.MEMORIES`; ``lanes`` and ``fifo_depth`` must be options of the
architecture the table names (default the streaming array, natively).
"""

from __future__ import annotations

from rvsm.model.fixed.build_settings import BUILD_SECTION, BuildSettings
from rvsm.model.infra.errors import RvsmError, shown
from rvsm.rtl.architectures.registry import (
    ARCHITECTURES,
    DEFAULT_ARCHITECTURE,
    INTERFACES,
    NATIVE,
    WRAPPERS,
)
from rvsm.rtl.fpga.build_budget import DEFAULT_DEVICE
from rvsm.rtl.fpga.devices import device_names, get_budget
from rvsm.rtl.fpga.flow import MEMORIES

__all__ = ["check_build_settings", "device_packages"]


def device_packages(device: str) -> list[str]:
    """The package names ``[rtl] package`` may take on ``device`` (the one device list):
    those of its I/O figures (:attr:`~rvsm.rtl.fpga.devices.DeviceBudget.io`), default
    first. An estimate-only part offers the one package its figures name (none when the
    package is only in the part name, as on the Gowin parts)."""
    names = [p.package for p in get_budget(device).io if not p.package.startswith("(")]
    return list(dict.fromkeys(names))


def _refuse(source: str, key: str, value: object, valid: str) -> RvsmError:
    return RvsmError(f"{source}: {BUILD_SECTION}.{key} = {shown(repr(value))} is not valid; "
                     f"{valid}")


def check_build_settings(settings: BuildSettings, source: str = "design point") -> None:
    """Refuse (:class:`RvsmError`, one line naming ``rtl.<key>`` and what is valid) a
    name no registry knows, an interface not offered for the architecture, or an option
    (``lanes``, ``fifo_depth``) that architecture does not take."""
    s = settings
    if s.arch is not None and s.arch not in ARCHITECTURES:
        raise _refuse(source, "arch", s.arch, f"choose one of {', '.join(ARCHITECTURES)}")
    arch = s.arch or DEFAULT_ARCHITECTURE
    if s.interface is not None and s.interface not in INTERFACES:
        raise _refuse(source, "interface", s.interface,
                      f"choose one of {', '.join(INTERFACES)}")
    interface = s.interface or NATIVE
    offered = [NATIVE, *(i for a, i in WRAPPERS if a == arch)]
    if interface not in offered:
        raise _refuse(source, "interface", s.interface,
                      f"arch {arch} is offered with {', '.join(offered)}")
    if s.device is not None and s.device not in device_names():
        raise _refuse(source, "device", s.device,
                      f"choose one of {', '.join(device_names())}")
    if s.package is not None:
        device = s.device or DEFAULT_DEVICE
        dev = f"{BUILD_SECTION}.device {device}" if s.device else f"the default device {device}"
        offered = device_packages(device)
        if s.package not in offered:
            raise _refuse(source, "package", s.package,
                          f"{dev} comes in {', '.join(offered)}" if offered else
                          f"{dev} names no package (estimate only, the package in its part "
                          f"name): leave {BUILD_SECTION}.package out")
    if s.memory is not None and s.memory not in MEMORIES:
        raise _refuse(source, "memory", s.memory, f"choose one of {', '.join(MEMORIES)}")
    built = ARCHITECTURES[arch] if interface == NATIVE else WRAPPERS[arch, interface]
    for key in ("lanes", "fifo_depth"):
        value = getattr(s, key)
        if value is not None and not built.takes(key):
            takes = ", ".join(o.name for o in built.options) or "no options"
            raise _refuse(source, key, value,
                          f"arch {arch} with interface {interface} takes {takes}")
