"""Top-level ports of any ``wiring.Component``, derived from its signature.

:func:`verilog_ports` names every flattened signature member by its path joined with
``_`` (``cfg.we`` -> ``cfg_we``) for Verilog generation; :func:`port_map` lists the same
ports with direction and width, plus the clock and reset of the ``sync`` domain, and
attaches a description to each from the component's own table, refusing ports without
one (and descriptions without a port), so the documentation cannot drift from the RTL.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

from amaranth.hdl import Shape, Value, ValueCastable
from amaranth.lib import wiring

from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.text_files import read_utf8_text

__all__ = ["load_ports_json", "port_map", "verilog_ports"]

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


#: Largest ``ports.json`` read (bytes): a port map is a few kB even at sensor scale.
PORTS_JSON_MAX_BYTES = 4 << 20


def load_ports_json(path: str | os.PathLike) -> dict:
    """Read a ``<top>.ports.json`` (``rvsm verilog``, build caches) and check its shape:
    an object with ``top`` (text), ``arch`` (text), ``latency`` (integer >= 0), an
    optional ``pixel_to_spike`` (integer >= 0; older maps have none) and
    ``ports`` (a list of ``name``/``dir``/``width``/``desc`` with optional ``fields`` of
    ``name``/``offset``/``width`` inside the port); :class:`RvsmError` naming the file and
    the first bad entry."""
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > PORTS_JSON_MAX_BYTES:
            raise RvsmError(f"{p}: {size} bytes is not a port map (at most "
                            f"{PORTS_JSON_MAX_BYTES} expected)")
        data = json.loads(read_utf8_text(p, "port map"))
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{p}: not valid JSON ({exc}); regenerate it with rvsm verilog") \
            from None
    except (OSError, RecursionError) as exc:
        raise RvsmError(f"{p}: cannot read the port map ({exc})") from None
    _check_ports_meta(data, str(p))
    return data


def _is_int(v: object, lo: int, hi: int) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi


def _check_ports_meta(data: object, source: str) -> None:
    def bad(what: str) -> RvsmError:
        return RvsmError(f"{source}: {what}; regenerate it with rvsm verilog")

    if not isinstance(data, dict):
        raise bad("a port map must be a JSON object")
    for key in ("top", "arch"):
        if not isinstance(data.get(key), str) or not data[key].isidentifier():
            raise bad(f"{key!r} must be an identifier")
    if not _is_int(data.get("latency"), 0, 1 << 20):
        raise bad("'latency' must be an integer >= 0")
    if "pixel_to_spike" in data and not _is_int(data["pixel_to_spike"], 0, 1 << 40):
        raise bad("'pixel_to_spike' must be an integer >= 0")
    ports = data.get("ports")
    if not isinstance(ports, list) or not ports:
        raise bad("'ports' must be a non-empty list")
    for i, port in enumerate(ports):
        if not (isinstance(port, dict) and isinstance(port.get("name"), str)
                and port["name"].isidentifier() and port.get("dir") in ("in", "out")
                and _is_int(port.get("width"), 1, 1 << 20)
                and isinstance(port.get("desc", ""), str)):
            raise bad(f"port {i} must have an identifier name, dir in/out and width >= 1")
        for j, f in enumerate(port.get("fields", [])) if isinstance(
                port.get("fields", []), list) else [(0, None)]:
            if not (isinstance(f, dict) and isinstance(f.get("name"), str)
                    and _is_int(f.get("offset"), 0, port["width"] - 1)
                    and _is_int(f.get("width"), 1, port["width"] - f["offset"])):
                raise bad(f"field {j} of port {port['name']!r} must have a name, an offset "
                          f"and a width inside the port")
    timing = data.get("timing", {})
    if not isinstance(timing, dict) or not all(
            isinstance(k, str) and _is_int(v, 0, 1 << 40) for k, v in timing.items()):
        raise bad("'timing' must map names to integers >= 0")
