"""Timing diagrams of the AXI IP, recorded from ``amaranth.sim`` runs (docs/ip.md).

Each scenario of :data:`SCENARIOS` drives a tiny IP (the ``fsm`` model's kernels on a
4x8 array, 2 lanes: lag 6 beats, 4 beats per row, 16 per frame) through
:mod:`rvsm.rtl.ip.drive` and records chosen ports and internal signals once per clock
cycle; :func:`scenario_waves` turns the recording into WaveJSON (one row per signal,
``=`` with a label for a bus, ``x`` where a bus carries nothing), the format WaveDrom
renders. The diagrams are therefore the RTL's behaviour, not a drawing of it:
``tests/rtl/ip/test_waves.py`` regenerates them and compares with ``docs/ip/*.json``.

``make diagrams`` (``scripts/timing_diagrams.py``) rewrites the JSON files and, when the
``wavedrom`` package is installed, their SVG renderings.
"""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.weights import model_contract
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.ip.drive import (
    Cycler,
    axil_write,
    input_stream,
    load_thresholds,
    run_bench,
    stream_beats,
    wait_idle,
)
from rvsm.rtl.ip.wrapper import RvsmAxisIp
from rvsm.rtl.wavejson import CycleTable

__all__ = ["SCENARIOS", "diagram_contract", "scenario_waves", "write_diagrams"]

LANES = 2


def diagram_contract() -> ArrayContract:
    """The diagrams' design: ``fsm`` kernels, 4x8 pixels, 4-bit ADC, 12-bit accumulators."""
    return model_contract("fsm", 4, 8, accumulator_bits=12)


@dataclass(frozen=True)
class _Row:
    """A recorded signal: its label, how to read it, and whether it is a bus (else a bit)
    with the bus' label function (value -> text, or None for no data)."""

    name: str
    read: Callable[[_Recorder], int]
    label: Callable[[int], str | None] | None = None


class _Recorder(Cycler):
    """A :class:`Cycler` that samples ``rows`` every cycle while ``recording``;
    ``beats`` counts the input handshakes so far (the index of the beat offered)."""

    def __init__(self, ctx: object, dut: RvsmAxisIp, rows: list[_Row]):
        super().__init__(ctx, dut)
        self.rows = rows
        self.samples: list[list[int]] = []
        self.recording = False
        self.beats = 0

    async def tick(self) -> None:
        if self.recording:
            self.samples.append([r.read(self) for r in self.rows])
        took = self.ctx.get(self.dut.s_axis.tvalid) and self.ctx.get(self.dut.s_axis.tready)
        await super().tick()
        self.beats += bool(took)


def _bit(get: Callable[[RvsmAxisIp], object]) -> Callable[[_Recorder], int]:
    return lambda r: int(r.ctx.get(get(r.dut)))


def _value(get: Callable[[RvsmAxisIp], object]) -> Callable[[_Recorder], int]:
    return lambda r: int(r.ctx.get(get(r.dut)))


def _when(valid: Callable[[RvsmAxisIp], object], get: Callable[[_Recorder], int]
          ) -> Callable[[_Recorder], int]:
    """``get`` while ``valid`` is high, else -1 (no data)."""
    return lambda r: get(r) if r.ctx.get(valid(r.dut)) else -1


def _position(dut: RvsmAxisIp, tdata: int) -> str:
    from rvsm.rtl.ip.axis import spike_tdata_layout

    c, geo = dut.contract, dut.geometry
    layout = spike_tdata_layout(c.num_scales, geo.lanes, c.height, geo.groups)
    row, group = (layout[k] for k in ("row", "group"))
    y = (tdata >> row.offset) & ((1 << row.shape.width) - 1)
    g = (tdata >> group.offset) & ((1 << group.shape.width) - 1)
    return f"{y},{g}"


def _label(v: int) -> str | None:
    return None if v < 0 else str(v)


def _stream_rows(dut: RvsmAxisIp) -> list[_Row]:
    """Both streams' ports: the input beat shown by its index, the output by (y,g)."""
    return [
        _Row("s_axis_tvalid", _bit(lambda d: d.s_axis.tvalid)),
        _Row("s_axis_tready", _bit(lambda d: d.s_axis.tready)),
        _Row("s_axis_tdata (beat)", _when(lambda d: d.s_axis.tvalid, lambda r: r.beats),
             _label),
        _Row("s_axis_tuser", _bit(lambda d: d.s_axis.tuser)),
        _Row("s_axis_tlast", _bit(lambda d: d.s_axis.tlast)),
        _Row("m_axis_tvalid", _bit(lambda d: d.m_axis.tvalid)),
        _Row("m_axis_tready", _bit(lambda d: d.m_axis.tready)),
        _Row("m_axis_tdata (y,g)", _when(lambda d: d.m_axis.tvalid,
                                         _value(lambda d: d.m_axis.tdata)),
             lambda v: None if v < 0 else _position(dut, v)),
        _Row("m_axis_tuser", _bit(lambda d: d.m_axis.tuser)),
        _Row("m_axis_tlast", _bit(lambda d: d.m_axis.tlast)),
    ]


def _level() -> _Row:
    return _Row("FIFO level", _value(lambda d: d.fifo.level), _label)


def _axil_rows() -> list[_Row]:
    return [_Row("s_axil_awvalid", _bit(lambda d: d.s_axil.awvalid)),
            _Row("s_axil_wvalid", _bit(lambda d: d.s_axil.wvalid)),
            _Row("s_axil_wdata", _when(lambda d: d.s_axil.wvalid,
                                       _value(lambda d: d.s_axil.wdata)),
                 lambda v: None if v < 0 else f"0x{v:X}"),
            _Row("s_axil_bvalid", _bit(lambda d: d.s_axil.bvalid))]


async def _setup(cy: Cycler, thresholds: np.ndarray, control: int = 0) -> None:
    await wait_idle(cy)
    await load_thresholds(cy, thresholds)
    if control:
        await axil_write(cy, cy.dut.regmap["CONTROL"].offset, control)
    for _ in range(3):
        await cy.tick()


def _record(fifo_depth: int, rows: Callable[[RvsmAxisIp], list[_Row]],
            body: Callable[[_Recorder, RvsmAxisIp, tuple], Awaitable[None]],
            steps: int = 1, flush: bool = True) -> tuple[RvsmAxisIp, list[_Row],
                                                          list[list[int]]]:
    c = diagram_contract()
    dut = RvsmAxisIp(c, LANES, fifo_depth)
    rng = np.random.default_rng(0)
    codes = rng.integers(0, 16, (steps, c.height, c.width))
    thr = rng.integers(1, 20, (c.num_scales, c.height, c.width))
    stream = input_stream(dut.geometry.schedule, codes, c.adc_bits, flush)
    chosen = rows(dut)
    box: list[_Recorder] = []

    async def bench(cy: Cycler) -> None:
        rec = _Recorder(cy.ctx, dut, chosen)
        box.append(rec)
        await body(rec, dut, (thr, *stream))

    run_bench(dut, bench)
    return dut, chosen, box[0].samples


async def _stream_scenario(rec: _Recorder, dut: RvsmAxisIp, args: tuple) -> None:
    thr, words, tuser, tlast = args
    await _setup(rec, thr)
    valid = [True] * 3 + [False] + [True] * 40
    ready = [True] * 11 + [False] * 7 + [True] * 40
    rec.mark, rec.ready, rec.recording = rec.cycle, ready, True
    await stream_beats(rec, words[:14], tuser[:14], tlast[:14], valid)
    for _ in range(4):
        await rec.tick()


async def _overflow_scenario(rec: _Recorder, dut: RvsmAxisIp, args: tuple) -> None:
    thr, words, tuser, tlast = args
    await _setup(rec, thr, dut.regmap.field("CONTROL", "drop").mask)
    ready = [True] * 8 + [False] * 12 + [True] * 40
    rec.mark, rec.ready = rec.cycle, ready
    rec.recording = True
    await stream_beats(rec, words[:18], tuser[:18], tlast[:18], ())
    for _ in range(4):
        await rec.tick()


async def _flush_scenario(rec: _Recorder, dut: RvsmAxisIp, args: tuple) -> None:
    thr, words, tuser, tlast = args
    await _setup(rec, thr)
    rm = dut.regmap
    await stream_beats(rec, words[:-2], tuser[:-2], tlast[:-2], ())
    rec.recording = True
    await stream_beats(rec, words[-2:], tuser[-2:], tlast[-2:], ())
    await axil_write(rec, rm["CONTROL"].offset, rm.field("CONTROL", "flush").mask
                     | rm.field("CONTROL", "clear").mask)
    for _ in range(10):
        await rec.tick()


async def _threshold_scenario(rec: _Recorder, dut: RvsmAxisIp, args: tuple) -> None:
    thr, words, tuser, tlast = args
    await _setup(rec, thr)
    rm, sched = dut.regmap, dut.geometry.schedule
    pause = sched.threshold_pause_beat(1)  # the frame boundary for thresholds
    await stream_beats(rec, words[:pause - 3], tuser[:pause - 3], tlast[:pause - 3], ())
    rec.recording = True
    await stream_beats(rec, words[pause - 3:pause], tuser[pause - 3:pause],
                       tlast[pause - 3:pause], ())
    await axil_write(rec, rm["THR_ADDR"].offset, 5)
    await axil_write(rec, rm.thr_data_registers()[-1].offset, 0x1FFFFF)
    await stream_beats(rec, words[pause:pause + 4], tuser[pause:pause + 4],
                       tlast[pause:pause + 4], ())
    for _ in range(2):
        await rec.tick()


def _control_rows(dut: RvsmAxisIp) -> list[_Row]:
    s = _stream_rows(dut)
    return [*s[:3], *_axil_rows(),
            _Row("STATUS.flushing", _bit(lambda d: d.flush_req)),
            _Row("array codes_valid", _bit(lambda d: d.array.codes.valid)),
            _Row("array clear", _bit(lambda d: d.array.clear)),
            s[5], s[7]]


def _threshold_rows(dut: RvsmAxisIp) -> list[_Row]:
    s = _stream_rows(dut)
    return [*s[:3], *_axil_rows(),
            _Row("array thr_we", _bit(lambda d: d.array.thr.we)),
            _Row("array thr_addr", _when(lambda d: d.array.thr.we,
                                         _value(lambda d: d.array.thr.addr)), _label),
            _Row("IN_BEATS", _value(lambda d: d.regs.value["IN_BEATS.count"]), _label)]


def _overflow_rows(dut: RvsmAxisIp) -> list[_Row]:
    s = _stream_rows(dut)
    return [*s[:3], _Row("array spikes_valid", _bit(lambda d: d.array.spikes.valid)),
            _level(), _Row("drop", _bit(lambda d: d.drop)), s[5], s[6], s[7],
            _Row("STATUS.overflow", _bit(lambda d: d.regs.value["STATUS.overflow"])),
            _Row("DROPPED", _value(lambda d: d.regs.value["DROPPED.count"]), _label)]


#: name -> (title, FIFO depth, signal rows, bench body, frames, flush beats sent).
SCENARIOS: dict[str, tuple] = {
    "stream": ("Input beats, output back-pressure (stall policy, FIFO 5): s_axis_tready "
               "falls when the FIFO has no room for the beats in flight; no beat is lost",
               5, lambda d: [*_stream_rows(d), _level()], _stream_scenario, 1, True),
    "overflow": ("Overflow (drop policy, FIFO 4): the input keeps its pace; beats that "
                 "find the FIFO full are dropped whole, STATUS.overflow and DROPPED count",
                 4, _overflow_rows, _overflow_scenario, 2, True),
    "flush_clear": ("End of a stream: the last beats, then CONTROL = flush | clear: lag "
                    "(6) zero beats inserted, s_axis_tready low, then a one-cycle clear",
                    8, _control_rows, _flush_scenario, 1, False),
    "threshold_write": ("A threshold write at a frame boundary: the source pauses after "
                        "threshold_pause_beat(1) = 17 beats, THR_ADDR and the data chunk "
                        "are written (the commit drives the array's thr bus), the stream "
                        "resumes: the new word applies from frame 1",
                        8, _threshold_rows, _threshold_scenario, 2, True),
}


def scenario_waves(name: str) -> dict:
    """The WaveJSON of scenario ``name`` (:data:`SCENARIOS`), from a fresh simulation."""
    title, depth, rows, body, steps, flush = SCENARIOS[name]
    _, chosen, samples = _record(depth, rows, body, steps, flush)
    table = CycleTable()
    for sample in samples:
        table.record({r.name: (r.label(v) if r.label else bool(v))
                      for r, v in zip(chosen, sample, strict=True)})
    waves = table.wavejson(title)
    waves["config"] = {"hscale": 1}
    return waves


def write_diagrams(out_dir: str | Path, render: bool = True) -> list[Path]:
    """Write ``<name>.json`` for every scenario into ``out_dir`` and, with ``render`` and
    the ``wavedrom`` package installed, ``<name>.svg``; returns the files written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name in SCENARIOS:
        waves = scenario_waves(name)
        text = json.dumps(waves, indent=1) + "\n"
        write_text_atomic(out / f"{name}.json", text)
        written.append(out / f"{name}.json")
        if render:
            try:
                import wavedrom  # type: ignore[import-not-found]
            except ImportError:
                continue
            svg = out / f"{name}.svg"
            wavedrom.render(json.dumps(waves)).saveas(str(svg))
            written.append(svg)
    return written
