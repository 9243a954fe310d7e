"""The SPI bridge's frame model (:mod:`rvsm.rtl.board.spi_model`) on its own: frame
bytes, the status byte, cut frames and unknown commands, against a register-file model."""

from __future__ import annotations

import pytest

from rvsm.rtl.board.spi_model import (
    READ_FRAME_BITS,
    WRITE_FRAME_BITS,
    SpiBridgeModel,
    SpiStatus,
    read_data,
    read_frame,
    write_frame,
)


class _Memory:
    """A bus of 32-bit words; address 0x10 is read-only (SLVERR on write)."""

    def __init__(self) -> None:
        self.words: dict[int, int] = {}

    def write(self, addr: int, data: int) -> int:
        if addr == 0x10:
            return 2
        self.words[addr] = data
        return 0

    def read(self, addr: int) -> tuple[int, int]:
        return self.words.get(addr, 0), 0


def test_frames_are_command_address_data_msb_first() -> None:
    assert write_frame(0x0A4, 0x12345678) == bytes([0x02, 0x00, 0xA4, 0x12, 0x34, 0x56, 0x78])
    assert read_frame(0x1FC) == bytes([0x03, 0x01, 0xFC, 0, 0, 0, 0, 0])
    assert (8 * len(write_frame(0, 0)), 8 * len(read_frame(0))) == (WRITE_FRAME_BITS,
                                                                    READ_FRAME_BITS)


def test_write_then_read_and_the_status_of_each() -> None:
    bus = _Memory()
    model = SpiBridgeModel(bus, 12)
    assert model.transfer(write_frame(0x84, 0xCAFE)) == bytes([0xA0]) + bytes(6)
    miso = model.transfer(read_frame(0x84))
    assert SpiStatus.decode(miso[0]) == SpiStatus(0, False, False)
    assert read_data(miso) == 0xCAFE and miso[1:4] == bytes(3)
    model.transfer(write_frame(0x10, 1))                      # refused by the bus
    assert SpiStatus.decode(model.transfer(read_frame(0x84))[0]).resp == 2
    model.transfer(write_frame(0x1000, 1))                    # beyond 12 address bits
    assert SpiStatus.decode(model.status()).resp == 2 and 0x1000 not in bus.words


def test_cut_frames_and_unknown_commands_are_bad_for_the_next_frame_only() -> None:
    bus = _Memory()
    model = SpiBridgeModel(bus, 12)
    assert model.transfer(write_frame(0x8, 5), bits=55) == bytes([0xA0]) + bytes(6)
    assert bus.words == {}                                    # 55 bits: nothing written
    assert SpiStatus.decode(model.transfer(bytes([0x7E, 0, 0]))[0]).bad  # the cut write
    assert SpiStatus.decode(model.transfer(read_frame(0x8))[0]).bad    # command 0x7E
    assert not SpiStatus.decode(model.status()).bad                    # the read: fine
    assert model.transfer(bytes(1), bits=4) == bytes([0xA0])  # a 4-bit blip: no transaction
    assert not SpiStatus.decode(model.status()).bad
    with pytest.raises(ValueError, match="no SPI slave"):
        SpiStatus.decode(0xFF)
