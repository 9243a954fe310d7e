"""The registry of RTL architectures, filled in explicitly (one line per architecture).

Every command (``rvsm verilog``, ``rvsm verify``, ``rvsm fpga``, ``rvsm formal``,
``rvsm mutate``), the co-simulation and the FPGA flow look an architecture up here once
(:func:`get_architecture`) and pass the :class:`~rvsm.rtl.capabilities.Architecture` on;
nothing else tests an architecture's name or its options to tell architectures apart.

An architecture is offered with interfaces (``--interface``): ``native``, its own ports,
and the wrappers registered with it, such as ``axis`` (the AXI4-Stream / AXI4-Lite IP
around the streaming array, :data:`rvsm.rtl.ip.architecture.STREAM_AXIS`):
``get_architecture("stream", "axis")``. A wrapper is an ``Architecture`` too (its own
component, port map, testbench) but not an ``--arch`` choice; it is found by its own
name as well (``stream_axis``, the name a port map records).

Adding an architecture is a package that defines one ``Architecture`` and one
:func:`register` call below (``docs/rtl.md``, "Adding an architecture").
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.ip.architecture import STREAM_AXIS
from rvsm.rtl.parallel.architecture import PARALLEL
from rvsm.rtl.stream.architecture import STREAM

__all__ = ["ARCHITECTURES", "DEFAULT_ARCHITECTURE", "INTERFACES", "NATIVE", "WRAPPERS",
           "architectures_with", "get_architecture", "register"]

#: Registered architectures by name (the ``--arch`` choices), in registration order.
ARCHITECTURES: dict[str, Architecture] = {}
#: The architecture every command builds unless told otherwise: the streaming array,
#: the one that reaches a full sensor.
DEFAULT_ARCHITECTURE = "stream"
#: The interface that is the architecture's own ports.
NATIVE = "native"
#: Every ``--interface`` choice: :data:`NATIVE` and each registered wrapper's.
INTERFACES: tuple[str, ...] = (NATIVE,)
#: The registered wrappers by (architecture name, interface).
WRAPPERS: dict[tuple[str, str], Architecture] = {}
#: Every architecture and wrapper by its own name.
_BY_NAME: dict[str, Architecture] = {}


def register(architecture: Architecture,
             interfaces: Mapping[str, Architecture] | None = None) -> Architecture:
    """Add ``architecture`` (its name must be new) with its wrappers by interface name
    (``{"axis": STREAM_AXIS}``; ``native`` is the architecture itself)."""
    global INTERFACES
    wrappers = dict(interfaces or {})
    for a in (architecture, *wrappers.values()):
        if a.name in _BY_NAME:
            raise ValueError(f"architecture {a.name!r} is already registered")
    if NATIVE in wrappers:
        raise ValueError(f"interface {NATIVE!r} is the architecture itself")
    ARCHITECTURES[architecture.name] = _BY_NAME[architecture.name] = architecture
    for interface, wrapper in wrappers.items():
        WRAPPERS[architecture.name, interface] = _BY_NAME[wrapper.name] = wrapper
        if interface not in INTERFACES:
            INTERFACES = (*INTERFACES, interface)
    return architecture


def get_architecture(name: str | Architecture = DEFAULT_ARCHITECTURE,
                     interface: str = NATIVE) -> Architecture:
    """The registered architecture called ``name`` (an :class:`Architecture` is taken as
    it is; a wrapper's own name finds the wrapper) offered with ``interface``;
    :class:`RvsmError` for an unknown name, an unknown interface, or an interface not
    registered for that architecture."""
    if isinstance(name, Architecture):
        architecture = name
    else:
        try:
            architecture = _BY_NAME[name]
        except KeyError:
            raise RvsmError(f"unknown architecture {name!r}; choose one of: "
                            f"{', '.join(ARCHITECTURES)}") from None
    if interface == NATIVE:
        return architecture
    if interface not in INTERFACES:
        raise RvsmError(f"unknown interface {interface!r}; choose one of: "
                        f"{', '.join(INTERFACES)}")
    try:
        return WRAPPERS[architecture.name, interface]
    except KeyError:
        bases = " or ".join(f"the {ARCHITECTURES[a].title} (--arch {a})"
                            for a, i in WRAPPERS if i == interface)
        raise RvsmError(f"--interface {interface} wraps {bases}, not --arch "
                        f"{architecture.name}") from None


def architectures_with(capability: Callable[[Architecture], object]) -> list[str]:
    """Names of the registered architectures (``--arch`` choices) that have
    ``capability`` (a truthy value of it), for messages such as "--protocol drives the
    stream architecture only"."""
    return [name for name, a in ARCHITECTURES.items() if capability(a)]


register(STREAM, interfaces={"axis": STREAM_AXIS})
register(PARALLEL)
