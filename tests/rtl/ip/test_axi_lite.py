"""The AXI4-Lite register file alone: AW and W in either order, reads beside writes."""

from __future__ import annotations

from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.ip.axi_lite import RESP_OKAY, RESP_SLVERR, AxiLiteRegisters
from rvsm.rtl.ip.register_map import ip_register_map
from tests.conftest import model_contract


def test_write_channels_in_either_order_and_a_read_meanwhile() -> None:
    c = model_contract("fsm", 4, 8)
    rm = ip_register_map(c, 2, 8, "0" * 16, "0" * 16, "0.1.0")
    dut = AxiLiteRegisters(rm)
    bus = dut.bus
    ctrl, data0 = rm["CONTROL"].offset, rm["THR_DATA0"].offset
    seen: dict[str, object] = {}

    async def write(ctx, addr: int, value: int, w_lead: int) -> int:  # noqa: ANN001
        """W ``w_lead`` cycles before AW (negative: after)."""
        ctx.set(bus.bready, 1)
        ctx.set(bus.awaddr, addr)
        ctx.set(bus.wdata, value)
        ctx.set(bus.wstrb, 0xF)
        aw_at, w_at = max(0, w_lead), max(0, -w_lead)
        aw_done = w_done = False
        cycle = 0
        while not (aw_done and w_done):
            ctx.set(bus.awvalid, cycle >= aw_at and not aw_done)
            ctx.set(bus.wvalid, cycle >= w_at and not w_done)
            aw_now = ctx.get(bus.awvalid) and ctx.get(bus.awready)
            w_now = ctx.get(bus.wvalid) and ctx.get(bus.wready)
            await ctx.tick()
            aw_done, w_done, cycle = aw_done or aw_now, w_done or w_now, cycle + 1
        ctx.set(bus.awvalid, 0)
        ctx.set(bus.wvalid, 0)
        while not ctx.get(bus.bvalid):
            await ctx.tick()
        resp = ctx.get(bus.bresp)
        await ctx.tick()
        return resp

    async def bench(ctx) -> None:  # noqa: ANN001
        seen["w_first"] = await write(ctx, data0, 0x155, 3)
        seen["aw_first"] = await write(ctx, ctrl, 0x4, -2)
        # a read issued while a write waits for its W channel
        ctx.set(bus.awaddr, data0)
        ctx.set(bus.awvalid, 1)
        ctx.set(bus.araddr, ctrl)
        ctx.set(bus.arvalid, 1)
        ctx.set(bus.rready, 1)
        await ctx.tick()
        ctx.set(bus.awvalid, 0)
        ctx.set(bus.arvalid, 0)
        while not ctx.get(bus.rvalid):
            await ctx.tick()
        seen["read"] = (ctx.get(bus.rdata), ctx.get(bus.rresp))
        await ctx.tick()
        ctx.set(bus.wdata, 0x2AA)
        ctx.set(bus.wvalid, 1)
        ctx.set(bus.bready, 1)
        await ctx.tick()
        ctx.set(bus.wvalid, 0)
        while not ctx.get(bus.bvalid):
            await ctx.tick()
        seen["late_w"] = ctx.get(bus.bresp)
        await ctx.tick()
        seen["data0"] = ctx.get(dut.value["THR_DATA0.data"])
        seen["drop"] = ctx.get(dut.value["CONTROL.drop"])

    run_simulation(dut, bench)
    assert seen["w_first"] == seen["aw_first"] == seen["late_w"] == RESP_OKAY
    assert seen["read"] == (0x4, RESP_OKAY)
    assert seen["data0"] == 0x2AA and seen["drop"] == 1


def test_read_and_write_latencies_and_arready_while_in_flight() -> None:
    """``rvalid`` from cycle 2 after the AR handshake (cycle 0), ``arready`` low until the
    R handshake; ``bvalid`` from cycle 3 after AW and W together; unmapped: SLVERR."""
    c = model_contract("fsm", 4, 8)
    rm = ip_register_map(c, 2, 8, "0" * 16, "0" * 16, "0.1.0")
    dut = AxiLiteRegisters(rm)
    bus = dut.bus
    seen: dict[str, object] = {}

    async def read(ctx, addr: int) -> tuple[int, int, list[int]]:  # noqa: ANN001
        ctx.set(bus.araddr, addr)
        ctx.set(bus.arvalid, 1)
        ctx.set(bus.rready, 0)
        assert ctx.get(bus.arready)
        await ctx.tick()
        ctx.set(bus.arvalid, 0)
        trace = []
        for _ in range(4):  # cycles 1..4, rready low: rvalid holds
            trace.append((ctx.get(bus.rvalid), ctx.get(bus.arready)))
            await ctx.tick()
        data, resp = ctx.get(bus.rdata), ctx.get(bus.rresp)
        ctx.set(bus.rready, 1)
        await ctx.tick()
        ctx.set(bus.rready, 0)
        return data, resp, trace

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(bus.awaddr, rm["THR_DATA0"].offset)
        ctx.set(bus.wdata, 0x123)
        ctx.set(bus.wstrb, 0xF)
        ctx.set(bus.awvalid, 1)
        ctx.set(bus.wvalid, 1)
        ctx.set(bus.bready, 1)
        await ctx.tick()
        ctx.set(bus.awvalid, 0)
        ctx.set(bus.wvalid, 0)
        seen["b"] = []
        for _ in range(4):
            seen["b"].append(ctx.get(bus.bvalid))
            await ctx.tick()
        seen["read"] = await read(ctx, rm["THR_DATA0"].offset)
        seen["unmapped"] = await read(ctx, 0xFFC)

    run_simulation(dut, bench)
    assert seen["b"] == [0, 0, 1, 0]
    data, resp, trace = seen["read"]
    assert (data, resp) == (0x123, RESP_OKAY)
    assert trace == [(0, 0), (1, 0), (1, 0), (1, 0)]
    assert seen["unmapped"][:2] == (0, RESP_SLVERR)
