"""amaranth.sim tests of the AXI IP against the fixed twin and the cycle model."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.flow_files import design_point_digest
from rvsm.rtl.ip.architecture import STREAM_AXIS
from rvsm.rtl.ip.axi_lite import RESP_OKAY, RESP_SLVERR
from rvsm.rtl.ip.drive import (
    Cycler,
    axil_read,
    axil_write,
    decode_output,
    input_stream,
    load_thresholds,
    read_register,
    run_bench,
    simulate_ip,
    stream_beats,
    wait_idle,
)
from rvsm.rtl.ip.model import pause_pattern, run_stream_model
from rvsm.rtl.ip.register_map import ID_MAGIC
from rvsm.rtl.ip.wrapper import RvsmAxisIp
from rvsm.rtl.stream.schedule import check_beats
from tests.conftest import model_contract

LANES = 2


def _run(model: str = "dog1", steps: int = 3, seed: int = 1, thr_hi: int = 60,
         height: int = 4) -> tuple[ArrayContract, np.ndarray, np.ndarray]:
    c = model_contract(model, height, 8)
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = rng.integers(1, thr_hi, (c.num_scales, c.height, c.width))
    return c, codes, thr


def _check_against_model(c: ArrayContract, codes: np.ndarray, thr: np.ndarray, drop: bool,
                         depth: int, valid: np.ndarray, ready: np.ndarray) -> tuple:
    """Run the RTL and the cycle model on the same patterns; every cycle and beat equal."""
    run = simulate_ip(c, LANES, codes, thr, fifo_depth=depth, drop=drop, valid=valid,
                      ready=ready)
    geo = run.dut.geometry
    sched = geo.schedule
    n_in = len(codes) * sched.beats_per_frame + geo.lag
    model = run_stream_model(n_in, geo.lag, depth, drop, valid, ready)
    assert run.accepted == model.accepted.tolist()
    assert [o[0] for o in run.out] == model.sent.tolist()
    beats, tuser, tlast, _ = decode_output(run.dut, run.out)
    twin = sched.expected_beats(c.run(codes, thr))
    pos = model.delivered
    assert np.array_equal(beats.spikes, twin[pos])  # each delivered beat whole, in order
    rows, groups = sched.positions(len(twin))
    assert np.array_equal(beats.rows, rows[pos]) and np.array_equal(beats.groups, groups[pos])
    assert np.array_equal(tuser, (rows[pos] == 0) & (groups[pos] == 0))
    assert np.array_equal(tlast, groups[pos] == sched.groups - 1)
    assert len(pos) + len(model.dropped) == len(twin)
    assert np.all(np.diff(pos) > 0)
    regs = run.registers
    assert regs["IN_BEATS"] == n_in
    assert regs["OUT_BEATS"] == len(pos)
    assert regs["DROPPED"] == len(model.dropped)
    return run, model


def test_stall_policy_delivers_every_beat_under_back_pressure() -> None:
    c, codes, thr = _run()
    valid, ready = pause_pattern(500, 0.3, 2), pause_pattern(500, 0.6, 3)
    run, model = _check_against_model(c, codes, thr, False, 4, valid, ready)
    assert len(model.dropped) == 0
    beats, *_ = decode_output(run.dut, run.out)
    result = check_beats(run.dut.geometry.schedule, c.run(codes, thr), beats)
    assert result["mismatches"] == 0 and result["compared"] == c.run(codes, thr).size
    # the credits stalled the input: some beat offered while the sink stalled waited
    assert model.cycles > len(codes) * 16 + run.dut.lag + 20
    assert run.registers["STATUS"] & 1 == 0


def test_drop_policy_drops_whole_beats_as_the_model_says() -> None:
    c, codes, thr = _run(seed=4)
    valid, ready = pause_pattern(500, 0.1, 5), pause_pattern(500, 0.6, 6)
    run, model = _check_against_model(c, codes, thr, True, 4, valid, ready)
    assert len(model.dropped) > 0
    status = run.registers["STATUS"]
    assert status & run.dut.regmap.field("STATUS", "overflow").mask


@pytest.mark.parametrize("depth", [RvsmAxisIp.FULL_RATE_DEPTH - 1,
                                   RvsmAxisIp.FULL_RATE_DEPTH])
def test_full_rate_when_the_sink_is_always_ready(depth: int) -> None:
    c, codes, thr = _run(steps=2)
    run, model = _check_against_model(c, codes, thr, False, depth, np.ones(0, bool),
                                      np.ones(0, bool))
    full_rate = run.accepted == list(range(len(run.accepted)))  # one beat per cycle
    assert full_rate == (depth >= RvsmAxisIp.FULL_RATE_DEPTH)
    assert run.out[0][0] - run.accepted[run.dut.lag] == RvsmAxisIp.RELEASE_CYCLES


def test_flush_and_clear_through_control() -> None:
    c, codes, thr = _run(model="fsm", steps=2)
    run = simulate_ip(c, LANES, codes, thr, flush="control",
                      ready=pause_pattern(300, 0.3, 8))
    beats, *_ = decode_output(run.dut, run.out)
    result = check_beats(run.dut.geometry.schedule, c.run(codes, thr), beats)
    assert result["mismatches"] == 0
    assert run.registers["IN_BEATS"] == codes.shape[0] * run.dut.geometry.beats_per_frame
    assert run.registers["STATUS"] == 0  # not busy, no flags


def test_registers_read_back() -> None:
    c, codes, thr = _run(model="dog4", steps=1)
    run = simulate_ip(c, LANES, codes, thr, fifo_depth=8)
    dut, regs = run.dut, run.registers
    assert regs["ID"] == ID_MAGIC
    assert regs["DIGEST_RTL"] == int(dut.rtl_digest[:8], 16)
    assert regs["DIGEST_POINT"] == int(design_point_digest(c)[:8], 16)
    assert regs["GEOMETRY0"] == c.height | c.width << 16
    assert regs["GEOMETRY1"] == (LANES | c.num_scales << 8 | c.adc_bits << 12
                                 | c.threshold_bits << 16 | c.accumulator_bits << 24)
    assert regs["TIMING"] == dut.lag | 8 << 16
    for r in dut.regmap.registers:  # constants read their declared value
        if all(f.access == "RO" and not f.live for f in r.fields):
            assert regs[r.name] == r.reset, r.name
    assert regs["THR_ADDR"] == 0  # wrapped after the last word
    last = dut.regmap.thr_data_registers()[-1]
    assert regs[last.name] != 0
    assert not any(run.load_responses)


def test_thresholds_after_reset_are_the_top_rail() -> None:
    """No threshold loaded: the IP's reset walk leaves the top rail (no spike until the
    accumulators saturate), the twin's thresholds of 2**(W-1)-1."""
    c, codes, _ = _run(model="fsm", steps=2)
    dut = RvsmAxisIp(c, LANES)
    top = np.full((c.num_scales, c.height, c.width), (1 << c.threshold_bits) - 1)
    words, tuser, tlast = input_stream(dut.geometry.schedule, codes, c.adc_bits, True)
    seen: dict[str, object] = {}

    async def bench(cy: Cycler) -> None:
        status = await read_register(cy, "STATUS")
        seen["init"] = bool(status & dut.regmap.field("STATUS", "init").mask)
        # a threshold commit while initialising is refused
        last = dut.regmap.thr_data_registers()[-1]
        seen["commit_resp"] = await axil_write(cy, last.offset, 1)
        await wait_idle(cy)
        seen["cycles"] = cy.cycle
        await stream_beats(cy, words, tuser, tlast, ())
        for _ in range(16):
            await cy.tick()

    cy = run_bench(dut, bench)
    assert seen["init"] and seen["commit_resp"] == RESP_SLVERR
    assert seen["cycles"] >= dut.init_cycles
    beats, *_ = decode_output(dut, cy.out)
    assert check_beats(dut.geometry.schedule, c.run(codes, top), beats)["mismatches"] == 0


def test_slave_errors_sticky_flags_and_framing() -> None:
    c, codes, thr = _run(model="fsm", steps=1, height=3)  # 12 words: 12 is out of range
    dut = RvsmAxisIp(c, LANES, fifo_depth=4)
    rm = dut.regmap
    words, tuser, tlast = input_stream(dut.geometry.schedule, codes, c.adc_bits, True)
    tuser = [1 - tuser[0], *tuser[1:]]  # a missing start of frame
    seen: dict[str, object] = {}

    async def bench(cy: Cycler) -> None:
        await wait_idle(cy)
        seen["unmapped_read"] = (await axil_read(cy, 0xFFC))[1]
        seen["unmapped_write"] = await axil_write(cy, 0xFFC, 1)
        seen["ro_write"] = await axil_write(cy, rm["ID"].offset, 1)
        seen["partial"] = await axil_write(cy, rm["CONTROL"].offset, 4, strb=0x1)
        seen["control"] = await read_register(cy, "CONTROL")
        seen["bad_scale"] = await axil_write(cy, rm["THR_ADDR"].offset, 1 << 16)
        seen["bad_word"] = await axil_write(cy, rm["THR_ADDR"].offset,
                                            dut.geometry.beats_per_frame)
        seen["good_addr"] = await axil_write(cy, rm["THR_ADDR"].offset, 3)
        seen["thr_addr"] = await read_register(cy, "THR_ADDR")
        await load_thresholds(cy, thr)
        # drop policy, the sink never ready: beats overflow the FIFO
        await axil_write(cy, rm["CONTROL"].offset, rm.field("CONTROL", "drop").mask)
        cy.mark, cy.ready = cy.cycle, np.zeros(1000, bool)
        await stream_beats(cy, words, tuser, tlast, ())
        for _ in range(8):
            await cy.tick()
        seen["status"] = await read_register(cy, "STATUS")
        seen["dropped"] = await read_register(cy, "DROPPED")
        await axil_write(cy, rm["STATUS"].offset, rm.field("STATUS", "overflow").mask)
        seen["status_after"] = await read_register(cy, "STATUS")

    run_bench(dut, bench)
    assert seen["unmapped_read"] == seen["unmapped_write"] == RESP_SLVERR
    assert seen["ro_write"] == seen["partial"] == RESP_SLVERR
    assert seen["control"] == 0  # the refused partial write changed nothing
    assert seen["bad_scale"] == seen["bad_word"] == RESP_SLVERR
    assert seen["good_addr"] == RESP_OKAY and seen["thr_addr"] == 3
    overflow = rm.field("STATUS", "overflow").mask
    framing = rm.field("STATUS", "framing").mask
    level = rm.field("STATUS", "fifo_level")
    assert seen["status"] & overflow and seen["status"] & framing
    assert (seen["status"] & level.mask) >> level.lsb == 4
    released = dut.geometry.beats_per_frame
    assert seen["dropped"] == released - 4  # the FIFO keeps the first 4
    assert not seen["status_after"] & overflow and seen["status_after"] & framing


def test_fifo_depth_is_checked() -> None:
    c, _, _ = _run(model="fsm")
    with pytest.raises(RvsmError, match="fifo-depth"):
        STREAM_AXIS.check(c, lanes=LANES, fifo_depth=RvsmAxisIp.MIN_FIFO_DEPTH - 1)
    STREAM_AXIS.check(c, lanes=LANES, fifo_depth=RvsmAxisIp.MIN_FIFO_DEPTH)


def _shared(c: ArrayContract, thresholds: tuple[int, ...]) -> ArrayContract:
    import dataclasses

    return dataclasses.replace(c, shared_thresholds=thresholds)


def test_shared_thresholds_load_by_scale_and_reset_to_the_nominal_ones() -> None:
    """threshold.storage = "shared": THR_ADDR a scale only, THR_DATA one threshold; the
    reset walk restores the nominal thresholds (S cycles), and a load of other values
    by scale spikes as the twin with them."""
    c, codes, _ = _run(model="dog2", steps=2)
    c = _shared(c, (9, 40))
    dut = RvsmAxisIp(c, LANES)
    assert [f.name for f in dut.regmap["THR_ADDR"].fields] == ["scale"]
    assert dut.regmap.thr_chunks == 1 and dut.init_cycles == c.num_scales
    nominal = np.broadcast_to(np.array(c.shared_thresholds)[:, None, None],
                              (c.num_scales, c.height, c.width))
    words, tuser, tlast = input_stream(dut.geometry.schedule, codes, c.adc_bits, True)

    async def bench(cy: Cycler) -> None:
        await wait_idle(cy)
        await stream_beats(cy, words, tuser, tlast, ())
        for _ in range(16):
            await cy.tick()

    cy = run_bench(dut, bench)
    beats, *_ = decode_output(dut, cy.out)
    assert check_beats(dut.geometry.schedule, c.run(codes, nominal), beats)["mismatches"] == 0
    loaded = np.broadcast_to(np.array([5, 70])[:, None, None], nominal.shape)
    run = simulate_ip(c, LANES, codes, loaded, fifo_depth=8)
    got, *_ = decode_output(run.dut, run.out)
    result = check_beats(run.dut.geometry.schedule, c.run(codes, loaded), got)
    assert result["mismatches"] == 0 and not any(run.load_responses)
    assert not np.array_equal(c.run(codes, loaded), c.run(codes, nominal))
    # a scale out of range is refused; the pattern of a per-pixel point cannot be loaded
    assert dut.regmap.field("THR_ADDR", "scale").max == 1
    with pytest.raises(RvsmError, match="shared"):
        dut.geometry.threshold_writes(np.arange(2 * c.height * c.width).reshape(
            2, c.height, c.width) + 1)


def test_extra_registers_of_a_wrapper_are_read_and_written_through_the_ip() -> None:
    """A board front end adds its registers (``extra_registers``): an ``RW`` one reads
    back what was written, a live ``RO`` one what the wrapper drives into
    ``regs.value``; the options and the RTL digest say they are there."""
    from rvsm.rtl.ip.register_map import Field, Register
    from rvsm.rtl.ip.wrapper import IP_ARCH, ip_options
    from rvsm.rtl.rtl_digest import rtl_digest

    c, _, _ = _run(model="fsm", steps=1)
    extra = (Register("LINK_STATUS", 0x80, (
                 Field("locked", 0, 1, "RO", 0, "link locked", live=True),), "link status"),
             Register("LINK_CTRL", 0x84, (
                 Field("enable", 0, 1, "RW", 0, "enable the link"),), "link control"))
    dut = RvsmAxisIp(c, LANES, extra_registers=extra)
    assert dut.options["extra_registers"][0]["name"] == "LINK_STATUS"
    assert dut.rtl_digest != rtl_digest(c, IP_ARCH, ip_options(LANES, dut.fifo_depth))
    seen: dict[str, int] = {}

    async def bench(cy: Cycler) -> None:
        cy.ctx.set(dut.regs.value["LINK_STATUS.locked"], 1)  # the wrapper's live value
        seen["write"] = await axil_write(cy, 0x84, 1)
        seen["ctrl"] = await read_register(cy, "LINK_CTRL")
        seen["status"] = await read_register(cy, "LINK_STATUS")
        seen["enable"] = cy.ctx.get(dut.regs.value["LINK_CTRL.enable"])

    run_bench(dut, bench)
    assert seen == {"write": RESP_OKAY, "ctrl": 1, "status": 1, "enable": 1}
