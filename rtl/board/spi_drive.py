"""An SPI master (mode 0) for ``amaranth.sim``: frames onto a
:class:`~rvsm.rtl.board.spi_bridge.SpiSignature` interface, MISO bytes back.

Times are in seconds, independent of the core clock, so the SCLK edges fall anywhere
in a core cycle (the bridge's sampling is exercised, not a lucky phase).
"""

from __future__ import annotations

from rvsm.rtl.board.spi_model import SpiStatus, read_data, read_frame, write_frame

__all__ = ["spi_read", "spi_transfer", "spi_write"]


async def spi_transfer(ctx, spi, mosi: bytes, half_period: float,  # noqa: ANN001
                       bits: int | None = None) -> bytes:
    """One frame: ``cs_n`` low, ``bits`` bits of ``mosi`` (default all) MSB first, each
    SCLK phase ``half_period`` s (also the lead, lag and idle times), ``cs_n`` high.
    MISO is sampled at each rising edge; returned as bytes (the last zero padded)."""
    n = 8 * len(mosi) if bits is None else bits
    value = int.from_bytes(mosi, "big")
    got = 0
    ctx.set(spi.cs_n, 0)
    for k in range(n):
        ctx.set(spi.mosi, value >> (8 * len(mosi) - 1 - k) & 1)
        await ctx.delay(half_period)
        got = got << 1 | ctx.get(spi.miso)
        ctx.set(spi.sclk, 1)
        await ctx.delay(half_period)
        ctx.set(spi.sclk, 0)
    await ctx.delay(half_period)
    ctx.set(spi.cs_n, 1)
    ctx.set(spi.mosi, 0)
    await ctx.delay(half_period)
    pad = -n % 8
    return (got << pad).to_bytes((n + pad) // 8, "big")


async def spi_write(ctx, spi, addr: int, data: int,  # noqa: ANN001
                    half_period: float) -> SpiStatus:
    """Write ``data`` to ``addr``; the status of the frames before it."""
    miso = await spi_transfer(ctx, spi, write_frame(addr, data), half_period)
    return SpiStatus.decode(miso[0])


async def spi_read(ctx, spi, addr: int, half_period: float) -> int:  # noqa: ANN001
    """The 32-bit value at ``addr`` (its response is in the next frame's status)."""
    return read_data(await spi_transfer(ctx, spi, read_frame(addr), half_period))
