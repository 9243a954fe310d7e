"""A Python model of the AXI4-Lite register file (:class:`~rvsm.rtl.ip.axi_lite.AxiLiteRegisters`):
what each write answers and what each read returns, from the
:class:`~rvsm.rtl.ip.register_map.RegisterMap` alone.

The rules it models (``docs/ip.md``): an address selects the register whose offset
matches it in bits ``[addr_bits-1:2]`` (the two low bits are ignored); a write answers
SLVERR, and changes nothing, for an unmapped address, a strobe other than 0xF, a
register without a writable field, a field above its ``max`` (judged on the field's span,
:meth:`~rvsm.rtl.ip.register_map.Register.span`) or a write the IP refuses; else OKAY,
and ``RW`` fields take the written bits, ``W1C`` fields clear the bits written 1, ``WO``
fields pulse (and read 0). A read answers SLVERR (data 0) for an unmapped address.
Fields whose value the IP drives (live ``RO``, ``external`` ``RW``) read ``inputs``.
"""

from __future__ import annotations

from collections.abc import Mapping

from rvsm.rtl.ip.register_map import RESP_OKAY, RESP_SLVERR, Field, Register, RegisterMap


def field_key(register: Register, field: Field) -> str:
    """``"REG.field"``, the key of :class:`~rvsm.rtl.ip.axi_lite.AxiLiteRegisters`' signals."""
    return f"{register.name}.{field.name}"


class RegisterFileModel:
    """The register file's state and responses. ``inputs``: the values of the fields the
    IP drives (live ``RO``, ``external`` ``RW``), by :func:`field_key`; default their reset."""

    def __init__(self, regmap: RegisterMap, inputs: Mapping[str, int] | None = None):
        self.regmap = regmap
        self.inputs = dict(inputs or {})
        self.values: dict[str, int] = {}
        for r in regmap.registers:
            for f in r.fields:
                if self._held_here(f):
                    self.values[field_key(r, f)] = f.reset

    @staticmethod
    def _held_here(f: Field) -> bool:
        return (f.access == "RW" and not f.external) or (f.access == "W1C")

    def register_at(self, addr: int) -> Register | None:
        """The register a byte address selects, or None (unmapped)."""
        word = (addr & ((1 << self.regmap.addr_bits) - 1)) >> 2
        for r in self.regmap.registers:
            if r.offset >> 2 == word:
                return r
        return None

    def write(self, addr: int, data: int, strb: int = 0xF, refused: bool = False) -> int:
        """Apply one write; its response."""
        r = self.register_at(addr)
        if r is None or not r.writable or strb != 0xF or refused:
            return RESP_SLVERR
        for f in r.fields:
            span = r.span(f)
            if f.max is not None and (data >> f.lsb) & ((1 << span) - 1) > f.max:
                return RESP_SLVERR
        for f in r.fields:
            bits = (data >> f.lsb) & ((1 << f.width) - 1)
            key = field_key(r, f)
            if f.access == "RW" and not f.external:
                self.values[key] = bits
            elif f.access == "W1C":
                self.values[key] &= ~bits
        return RESP_OKAY

    def field_value(self, register: Register, field: Field) -> int:
        """What a read returns in ``field``'s bits."""
        key = field_key(register, field)
        if field.access == "WO":
            return 0
        if key in self.values:
            return self.values[key]
        if field.access == "RO" and not field.live:
            return field.reset
        return self.inputs.get(key, field.reset)

    def read(self, addr: int) -> tuple[int, int]:
        """One read: ``(data, response)``."""
        r = self.register_at(addr)
        if r is None:
            return 0, RESP_SLVERR
        return sum(self.field_value(r, f) << f.lsb for f in r.fields), RESP_OKAY
