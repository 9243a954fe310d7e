"""The registry of RTL architectures, filled in explicitly (one line per architecture).

Every command (``rvsm verilog``, ``rvsm verify``, ``rvsm fpga``), the co-simulation and
the FPGA flow look an architecture up here by name (:func:`get_architecture`); none
tests options such as ``lanes`` to tell architectures apart. Adding an architecture is
a package that defines one :class:`~rvsm.rtl.capabilities.Architecture` and one
:func:`register` call below (``docs/rtl.md``, "Adding an architecture").
"""

from __future__ import annotations

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.parallel.architecture import PARALLEL
from rvsm.rtl.stream.architecture import STREAM

__all__ = ["ARCHITECTURES", "DEFAULT_ARCHITECTURE", "get_architecture", "register"]

#: Registered architectures by name, in registration order (the default first).
ARCHITECTURES: dict[str, Architecture] = {}
#: The architecture every command builds unless told otherwise: the streaming array,
#: the one that reaches a full sensor.
DEFAULT_ARCHITECTURE = "stream"


def register(architecture: Architecture) -> Architecture:
    """Add ``architecture`` to the registry (its name must be new)."""
    if architecture.name in ARCHITECTURES:
        raise ValueError(f"architecture {architecture.name!r} is already registered")
    ARCHITECTURES[architecture.name] = architecture
    return architecture


def get_architecture(name: str | Architecture = DEFAULT_ARCHITECTURE) -> Architecture:
    """The registered architecture called ``name`` (an :class:`Architecture` is returned
    as it is); :class:`RvsmError` for an unknown name."""
    if isinstance(name, Architecture):
        return name
    try:
        return ARCHITECTURES[name]
    except KeyError:
        raise RvsmError(f"unknown architecture {name!r}; choose one of: "
                        f"{', '.join(ARCHITECTURES)}") from None


register(STREAM)
register(PARALLEL)
