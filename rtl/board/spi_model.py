"""The SPI register bridge's frame protocol and its bit-accurate model (pure Python).

:class:`~rvsm.rtl.board.spi_bridge.SpiBridge` is tested against :class:`SpiBridgeModel`.
SPI mode 0 (``sclk`` idles low, both sides sample on the rising edge and change on the
falling edge), most significant bit first, one transaction per frame (``cs_n`` low):

* **write**: ``0x02``, address (2 bytes), data (4 bytes): 7 bytes, 56 SCLK cycles. The
  AXI4-Lite write (strobe 0xF) starts once the 56th bit is in; a frame that ends
  earlier writes nothing.
* **read**: ``0x03``, address (2 bytes), one turnaround byte (any value), then 4 bytes
  during which MISO carries the data: 8 bytes, 64 SCLK cycles. The AXI4-Lite read starts
  once the address is in; the turnaround byte gives it 8 SCLK cycles.
* MISO during the command byte is the **status** of the frames before:
  ``0xA0 | bad << 3 | late << 2 | resp`` (``0xA`` marks a slave that is there: a stuck
  line reads 0x00 or 0xFF). ``resp`` is the AXI response of the last transaction (OKAY 0,
  SLVERR 2; an address above the bus's ``addr_bits`` is answered SLVERR without a bus
  transaction); ``bad``: the last frame had an unknown command or ended before its
  transaction began (a write's 56th bit, a read's 24th; a frame of fewer than 8 bits is
  ignored); ``late``: a read's data was not back in time (it read 0), or a
  transaction arrived while the bus was still busy. ``bad`` and ``late`` describe the
  previous frame only. MISO is 0 elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

__all__ = ["ADDRESS_BYTES", "READ", "READ_FRAME_BITS", "STATUS_MARK", "WRITE",
           "WRITE_FRAME_BITS", "SpiBridgeModel", "SpiStatus", "read_data", "read_frame",
           "write_frame"]

#: Command bytes.
WRITE, READ = 0x02, 0x03
#: Address bytes (16 bits, most significant byte first).
ADDRESS_BYTES = 2
#: Bits of a whole write frame and of a whole read frame.
WRITE_FRAME_BITS = 8 * (1 + ADDRESS_BYTES + 4)
READ_FRAME_BITS = 8 * (1 + ADDRESS_BYTES + 1 + 4)
#: High nibble of every status byte.
STATUS_MARK = 0xA0
#: Status bits.
LATE, BAD = 0x04, 0x08
#: AXI responses.
OKAY, SLVERR = 0b00, 0b10


class RegisterBus(Protocol):
    """An AXI4-Lite slave as the model sees it (e.g.
    :class:`~rvsm.rtl.ip.register_model.RegisterFileModel`)."""

    def write(self, addr: int, data: int) -> int: ...
    def read(self, addr: int) -> tuple[int, int]: ...


def write_frame(addr: int, data: int) -> bytes:
    """MOSI bytes of a write of ``data`` (32 bits) to byte address ``addr`` (16 bits)."""
    return bytes([WRITE]) + (addr & 0xFFFF).to_bytes(2, "big") + (data & 0xFFFFFFFF) \
        .to_bytes(4, "big")


def read_frame(addr: int) -> bytes:
    """MOSI bytes of a read of byte address ``addr`` (16 bits): command, address,
    turnaround and four bytes during which MISO carries the data."""
    return bytes([READ]) + (addr & 0xFFFF).to_bytes(2, "big") + bytes(5)


def read_data(miso: bytes) -> int:
    """The 32-bit data of a read frame's MISO bytes."""
    return int.from_bytes(miso[4:8], "big")


@dataclass(frozen=True)
class SpiStatus:
    """A status byte decoded: ``resp`` (last AXI response), ``late``, ``bad``."""

    resp: int
    late: bool
    bad: bool

    @classmethod
    def decode(cls, byte: int) -> SpiStatus:
        """Raises ``ValueError`` when the byte lacks :data:`STATUS_MARK` (no slave)."""
        if byte & 0xF0 != STATUS_MARK:
            raise ValueError(f"status byte 0x{byte:02X} lacks the 0xA0 mark: no SPI slave "
                             "answers (check cs_n, sclk and miso)")
        return cls(byte & 3, bool(byte & LATE), bool(byte & BAD))


class SpiBridgeModel:
    """The bridge's behaviour at legal timing (``docs/board.md``): :meth:`transfer` takes
    one frame's MOSI bits and gives its MISO bits, doing the frame's transaction on
    ``bus``; ``addr_bits`` is the bus's address width."""

    def __init__(self, bus: RegisterBus, addr_bits: int):
        self.bus = bus
        self.addr_bits = addr_bits
        self.resp = OKAY
        self.flags = 0

    def status(self) -> int:
        """The status byte the next frame shifts out first."""
        return STATUS_MARK | self.flags | self.resp

    def transfer(self, mosi: bytes, bits: int | None = None) -> bytes:
        """One frame: ``mosi`` bytes, of which the first ``bits`` bits are clocked
        (default all); MISO as bytes (the last one zero padded)."""
        n = 8 * len(mosi) if bits is None else bits
        value = int.from_bytes(mosi, "big") >> (8 * len(mosi) - n) if n else 0
        out = self.status() << max(0, n - 8) if n >= 8 else self.status() >> (8 - n)
        self.flags = 0
        cmd = value >> (n - 8) & 0xFF if n >= 8 else None
        addr = value >> (n - 24) & 0xFFFF if n >= 24 else None
        in_range = addr is not None and addr >> self.addr_bits == 0
        if cmd == WRITE:
            if n >= WRITE_FRAME_BITS:
                data = value >> (n - WRITE_FRAME_BITS) & 0xFFFFFFFF
                self.resp = self.bus.write(addr, data) if in_range else SLVERR
            else:
                self.flags = BAD
        elif cmd == READ:
            if addr is None:
                self.flags = BAD
            else:
                data, resp = self.bus.read(addr) if in_range else (0, SLVERR)
                self.resp = resp
                if n > 32:
                    take = min(32, n - 32)
                    out |= (data >> (32 - take)) << (n - 32 - take)
        elif cmd is not None:
            self.flags = BAD
        pad = -n % 8
        return (out << pad).to_bytes((n + pad) // 8, "big")
