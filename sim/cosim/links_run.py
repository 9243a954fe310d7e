"""A design point through both board links, the simulator doing the per-bit work.

:func:`links_verify` builds :class:`~rvsm.rtl.board.loopback.LinkLoopback` (sensor
serialiser, :class:`~rvsm.rtl.board.front_end.BoardFrontEnd`, board deserialiser; skew
between the receive pairs and a bit slip) inside the long-run harness
(:mod:`rvsm.sim.cosim.builds.chunk_harness`: chunks of beats from files, spikes to
files), runs :mod:`rvsm.sim.cosim.long_runs.tb_links` through the cocotb adapter on
Icarus or Verilator, and checks every spike that comes back through the transmit link
against the fixed twin (:meth:`ArrayContract.run`, :func:`check_beats`). Builds are
cached in ``build_root`` by the RTL digest, the harness version and the simulator.
"""

from __future__ import annotations

import json
import resource
import shutil
import time
from pathlib import Path

import numpy as np
from amaranth.back import verilog as amaranth_verilog

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.board.loopback import CORE_BITS, LinkLoopback
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.rtl_digest import rtl_digest
from rvsm.sim.cosim.builds.chunk_harness import (
    DEFAULT_DEPTH,
    HARNESS_TOP,
    HARNESS_VERSION,
    HarnessLayout,
    clock_inside,
    harness_verilog,
)
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator, cocotb_build, cocotb_test, cxx_opt
from rvsm.sim.cosim.builds.icarus_netlist import write_icarus_netlist
from rvsm.sim.cosim.long_runs.chunk_files import encode_threshold_writes

#: The streaming array's beats (the front end's array): their checker and type.
_BEATS = get_architecture().beats

__all__ = ["TOP", "links_build", "links_verify"]

#: The loopback's module name.
TOP = "rvsm_link_loopback"
TESTBENCH = "rvsm.sim.cosim.long_runs.tb_links"
#: Bit-clock cycles the harness waits after a chunk's last beat (the loop's latency,
#: tens of core cycles, with room to spare).
TAIL_CYCLES = 256 * CORE_BITS
#: Beats per chunk (the harness holds DEFAULT_DEPTH; the lag's outputs fit beside).
CHUNK_BEATS = DEFAULT_DEPTH - 1024


def _layout(lb: LinkLoopback) -> HarnessLayout:
    thr = {n: len(getattr(lb.thr, n)) for n in lb.thr.signature.members}
    widths = {"clk": 1, "rst": 1, "clear": 1, "codes_valid": 1, "codes_ready": 1,
              "codes_payload": len(lb.codes.payload.as_value()), "spikes_valid": 1,
              "spikes_payload": len(lb.spikes.payload.as_value()),
              "thr_we": thr["we"], "thr_addr": thr["addr"], "thr_data": thr["data"]}
    fields = {name: (f.offset, f.width) for name, f in lb.geometry.spike_layout}
    return HarnessLayout(TOP, widths, fields, DEFAULT_DEPTH, tail=TAIL_CYCLES,
                         thr_every=2 * CORE_BITS)


def links_build(point: DesignPoint, lanes: int, sim: str, build_root: str | Path,
                delays: tuple[int, ...] | None = None) -> tuple[Path, LinkLoopback, dict]:
    """The loopback of ``point`` at ``lanes`` built for ``sim`` in the harness (cached);
    returns the build folder, the loopback and timings (``generate``, ``build`` s, 0
    when cached)."""
    check_simulator(sim)
    c = point.contract()
    lb = LinkLoopback(c, lanes, delays=delays)
    key = rtl_digest(c, "links", {"lanes": lanes, "delays": list(lb.delays),
                                  "harness": HARNESS_VERSION, "sim": sim,
                                  "opt": cxx_opt(True) if sim == "verilator" else ""})
    final = Path(build_root).resolve() / f"links-{sim}-{key}"
    times = {"generate": 0.0, "build": 0.0}
    if (final / "done").exists():
        return final, lb, times
    work = final.with_name(final.name + ".tmp")
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    t0 = time.perf_counter()
    verilog = work / f"{TOP}.v"
    # Amaranth's own memories: an EnableInserter reaches their ports (the project's
    # fast path, :func:`convert_verilog`, makes them instances, which it does not)
    verilog.write_text(amaranth_verilog.convert(lb, name=TOP, ports=verilog_ports(lb),
                                                emit_src=False))
    source = verilog
    if sim == "icarus":  # processes as cells (:mod:`.builds.icarus_netlist`)
        source = work / f"{TOP}.icarus.v"
        write_icarus_netlist(verilog, TOP, source, work / "yosys.log")
    layout = _layout(lb)
    harness = work / f"{HARNESS_TOP}.v"
    harness.write_text(harness_verilog(layout, clock_inside(sim)))
    times["generate"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    cocotb_build(sim, [source, harness], HARNESS_TOP, layout.ports, work / "sim_build",
                 False, work / "build.log", long_run=True)
    times["build"] = time.perf_counter() - t0
    (work / "done").write_text(json.dumps(times))
    shutil.rmtree(final, ignore_errors=True)
    work.rename(final)
    return final, lb, times


def links_verify(point: DesignPoint, lanes: int, steps: int, work_dir: str | Path,
                 sim: str = "icarus", seed: int = 0, build_root: str | Path | None = None,
                 delays: tuple[int, ...] | None = None,
                 flip: tuple[int, int, int, int] | None = None) -> dict:
    """Run ``steps`` random frames of ``point`` through the loopback on ``sim``; return
    ``steps``, ``compared``, ``spikes`` (non-zero), ``mismatches``, ``first_mismatch``,
    the harness's ``cycles`` (bit clocks), ``stray``, ``overflow``, ``seconds`` (phases)
    and ``peak_rss_mb`` (this process and the simulator's). On a mismatch an Icarus run
    is simulated again with the harness's dump on for the window before the first
    mismatching beat (two frames and the lag, in bit clocks) and 64 cycles after it:
    ``waveform`` (an FST; ``None`` on Verilator, whose build has no tracing) and
    ``window_cycles``. ``flip`` = (step, scale, row, column) changes that expected spike
    (the failure path, for tests). :class:`ToolError` when the simulator writes no
    result."""
    t_start = time.perf_counter()
    work = Path(work_dir).resolve()
    work.mkdir(parents=True, exist_ok=True)
    build_dir, lb, times = links_build(point, lanes, sim, build_root or work / "builds",
                                       delays)
    c, geo = lb.contract, lb.geometry
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width), dtype=np.int64)
    thr = point.integer_thresholds()
    expected = c.run(codes, thr)
    if flip is not None:
        expected[flip] = 0 if expected[flip] else 1
    times["twin"] = time.perf_counter() - t0
    beats = np.concatenate([codes.reshape(-1, geo.lanes),
                            np.zeros((geo.lag, geo.lanes), np.int64)]).astype(np.uint32)
    run = work / "run"
    shutil.rmtree(run, ignore_errors=True)
    run.mkdir()
    writes = lb.dut.threshold_writes(thr)
    layout = _layout(lb)
    (run / "thresholds.hex").write_bytes(encode_threshold_writes(
        writes, layout.widths["thr_addr"], layout.widths["thr_data"]))
    setup = run / "links.npz"
    np.savez(setup, beats=beats, chunk=CHUNK_BEATS, adc_bits=c.adc_bits,
             in_bits=layout.in_bits, out_bits=layout.out_bits + 32, thr_count=len(writes),
             clock_outside=int(not clock_inside(sim)))
    t0 = time.perf_counter()
    result, out = _simulate(sim, build_dir, run, setup, [])
    times["simulate"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    got = _beats(out, layout, c.num_scales, geo.lanes)
    check = _BEATS.check_beats(geo.schedule, expected, got)
    times["check"] = time.perf_counter() - t0
    waveform, window = None, None
    first = check.get("first_mismatch")
    if first is not None and sim == "icarus":
        cycle = int((out[first["beat"], layout.out_bits:].astype(np.int64)
                     << np.arange(32)).sum())
        window = [max(0, cycle - (2 * geo.beats_per_frame + geo.lag) * CORE_BITS),
                  cycle + 64]
        again = work / "failure"
        shutil.rmtree(again, ignore_errors=True)
        shutil.copytree(run, again, ignore=shutil.ignore_patterns("*.hex", "*.npy"))
        shutil.copy(run / "thresholds.hex", again / "thresholds.hex")
        waveform = again / "window.fst"
        _simulate(sim, build_dir, again, again / "links.npz",
                  [f"+rvsm_dump_file={waveform}", f"+rvsm_dump_from={window[0]}",
                   f"+rvsm_dump_to={window[1]}"])
    times["total"] = time.perf_counter() - t_start
    peak = max(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
               resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
    return {"point": f"{c.height}x{c.width}", "lanes": geo.lanes, "sim": sim,
            "steps": steps, "rx_pairs": lb.rx_format.pairs, "tx_pairs": lb.tx_format.pairs,
            "delays": list(lb.delays), "compared": int(check["compared"]),
            "spikes": int(np.count_nonzero(expected)),
            "mismatches": int(check["mismatches"]) + result["stray"] + result["overflow"],
            "first_mismatch": check.get("first_mismatch"), "beats_out": result["beats_out"],
            "cycles": result["cycles"], "core_cycles": result["cycles"] // CORE_BITS,
            "stray": result["stray"], "overflow": result["overflow"],
            "waveform": None if waveform is None else str(waveform),
            "window_cycles": window,
            "chunks": result["chunks"], "seconds": times, "peak_rss_mb": round(peak, 1)}


def _simulate(sim: str, build_dir: Path, run: Path, setup: Path, plusargs: list[str]
              ) -> tuple[dict, np.ndarray]:
    """Run the testbench in ``run``: its JSON result and the output beats' bits; with
    ``plusargs`` (a dump window) the simulator's dumps are on (FST on Icarus)."""
    out_path, result_path = run / "out.npy", run / "result.json"
    cocotb_test(sim, build_dir / "sim_build", HARNESS_TOP, TESTBENCH, run,
                {"RVSM_LINKS": str(setup), "RVSM_OUT": str(out_path),
                 "RVSM_RESULT": str(result_path)}, bool(plusargs), plusargs,
                run / "results.xml",
                run / "sim.log")
    try:
        return json.loads(result_path.read_text()), np.load(out_path)
    except (OSError, ValueError):
        raise ToolError(f"the links testbench wrote no result; log: {run / 'sim.log'}") \
            from None


def _beats(bits: np.ndarray, layout: HarnessLayout, scales: int, lanes: int) -> object:
    """Output beats ``(K, out_bits + 32)`` little-endian bit columns as OutputBeats."""
    def field(name: str) -> np.ndarray:
        off, width = layout.fields[name]
        return bits[:, off:off + width]

    def value(name: str) -> np.ndarray:
        b = field(name).astype(np.int64)
        return (b << np.arange(b.shape[1])).sum(axis=1)

    sp = scales * lanes
    spikes = field("pos").astype(np.int8) - field("neg").astype(np.int8)
    return _BEATS.output_beats(value("row"), value("group"), value("last").astype(bool),
                       spikes.reshape(len(bits), scales, lanes)[:, :, :sp // scales])
