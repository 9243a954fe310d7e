"""Top-level ports of any ``wiring.Component``, derived from its signature.

:func:`verilog_ports` names every flattened signature member by its path joined with
``_`` (``cfg.we`` -> ``cfg_we``) for Verilog generation; :func:`port_map` lists the same
ports with direction and width, plus the clock and reset of the ``sync`` domain, and
attaches a description to each from the component's own table, refusing ports without
one (and descriptions without a port), so the documentation cannot drift from the RTL.
"""

from __future__ import annotations

from collections.abc import Mapping

from amaranth.hdl import Shape, Value, ValueCastable
from amaranth.lib import wiring

__all__ = ["port_map", "verilog_ports"]

#: Implicit ports of the ``sync`` domain in Amaranth's generated Verilog.
SYNC_PORTS = ("clk", "rst")


def _flat(component: wiring.Component, sep: str) -> list[tuple[str, Value]]:
    out = []
    for path, _, value in component.signature.flatten(component):
        if isinstance(value, ValueCastable):
            value = value.as_value()
        out.append((sep.join(map(str, path)), value))
    return out


def verilog_ports(
    component: wiring.Component, sep: str = "_"
) -> dict[str, tuple[Value, None]]:
    """``{name: (value, None)}`` for ``amaranth.back.verilog.convert(ports=...)``.

    The direction is left to Amaranth (``None``: a port the design drives is an output,
    any other an input), which agrees with the signature because every ``Out`` member
    of the arrays is driven; :func:`port_map` states the signature's direction.
    """
    return {name: (value, None) for name, value in _flat(component, sep)}


def port_map(
    interface: wiring.Signature | wiring.Component, docs: Mapping[str, str], sep: str = "_"
) -> list[dict]:
    """Ports in Verilog order: ``name``, ``dir`` (in/out), ``width``, ``desc``.

    ``interface`` is a component's signature (or the component). ``docs`` maps every
    port name (``clk`` and ``rst`` of the ``sync`` domain included) to its meaning; a
    port without a description, or a description without a port, raises
    :class:`ValueError`.
    """
    signature = interface if isinstance(interface, wiring.Signature) else interface.signature
    rows = [{"name": n, "dir": "in", "width": 1} for n in SYNC_PORTS]
    rows += [
        {"name": sep.join(map(str, path)), "dir": "in" if member.flow == wiring.In else "out",
         "width": Shape.cast(member.shape).width}
        for path, member in signature.members.flatten() if member.is_port
    ]
    names = [r["name"] for r in rows]
    missing = [n for n in names if n not in docs]
    extra = [n for n in docs if n not in names]
    if missing or extra:
        raise ValueError(f"port descriptions out of step with the signature: missing "
                         f"{missing}, unknown {extra}")
    return [{**r, "desc": docs[r["name"]]} for r in rows]
