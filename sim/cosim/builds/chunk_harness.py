"""The long-run harness: a simulation-only Verilog source and sink around the streaming
array, so the simulator, not Python, runs every clock cycle.

:func:`harness_verilog` writes module ``rvsm_chunk_harness`` (:data:`HARNESS_TOP`) from
the array's port map (``<top>.ports.json``): it instantiates the array and adds

* an input memory of :data:`DEFAULT_DEPTH` beats, filled by ``$readmemh`` from the file
  named by ``+rvsm_chunk_in=`` when ``start`` is seen high on a rising edge with ``count``
  (1 .. depth) beats; it then presents them back to back on ``codes`` (valid high while
  beats remain; a beat moves on when ``codes_ready`` takes it);
* an output memory: every cycle with ``spikes_valid`` high stores ``{cycle[31:0],
  spikes_payload}`` (the clock-cycle counter since reset, then the beat) while a chunk
  runs; ``stray`` counts beats presented while no chunk runs (a correct array never
  presents one: each output beat follows its input beat by one cycle);
* ``TAIL`` cycles after the chunk's last beat is taken, ``$writememh`` of the
  ``out_count`` stored beats to ``+rvsm_chunk_out=`` and ``done`` high (until the next
  ``start``); ``overflow`` is set if a chunk presented more beats than the memory holds;
* the thresholds, loaded by the harness itself: when ``thr_load`` is seen high on a
  rising edge with ``thr_count`` words, ``$readmemh`` of ``+rvsm_thr_in=`` (default
  ``thresholds.hex``: one ``{addr, data}`` word per line, :func:`encode_threshold_writes`)
  and one write per cycle on the array's ``thr_we/thr_addr/thr_data`` from the next
  cycle on (what the testbench did from Python, one wakeup per cycle: 0.3 s at 64x64 on
  Icarus, against 0.02 s here), then ``done`` high. The harness's own ``thr_*`` inputs
  reach the array when no load runs;
* Verilator code coverage leaves the harness out (``verilator coverage_off``): the
  figures are the array's.
* with ``clock_inside`` (Icarus builds, :func:`clock_inside`), the harness makes ``clk``
  itself (an output: ``initial`` ... ``forever #5 clk = ~clk``, rising edges at 0, 10,
  20 ns ... as cocotb's ``Clock`` drives them) and the testbench starts no clock: on
  Icarus cocotb 2.1's ``Clock`` is a Python coroutine woken twice per cycle (its C++
  ``gpi`` clock only with ``COCOTB_TRUST_INERTIAL_WRITES``): with the Icarus netlist,
  4,648 -> 5,584 cycles per CPU second of the simulator's thread, 12.0 -> 6.8 s of
  simulation on a quieter machine (docs/long-runs.md); Verilator builds keep the input
  (a delay needs ``--timing``);
* the array's state, for a segment of a sharded run (:mod:`rvsm.sim.cosim.long_runs.shards`):
  ``state_load`` high at a rising edge: at the next falling edge, ``$readmemh`` of every
  accumulator and threshold memory bank from ``state_in/<acc|thr>_s<S>.b<K>.hex`` by
  hierarchical name (:func:`state_memories`: the banks as the array's Verilog declares
  them), and the fresh-frame flag cleared (the first frame after reset then reads the
  loaded accumulators, as a run that reached this step would); ``state_dump`` likewise
  ``$writememh`` of every bank to ``state_out/``. Both reach into the simulation only:
  the array has no port for them;
* ``+rvsm_dump_file=F +rvsm_dump_from=C0 +rvsm_dump_to=C1``: a waveform (VCD) of the
  array's ports and internals for clock cycles ``C0 .. C1`` only (``$dumpvars`` at
  ``C0``, ``$dumpoff`` after ``C1``), the window around a mismatch of a long run.

The testbench (:mod:`rvsm.sim.cosim.long_runs.tb_stream_chunks`) therefore wakes up a few times
per chunk, not per cycle. Chunk files are hexadecimal text, one beat per line, most
significant digit first (:mod:`rvsm.sim.cosim.long_runs.chunk_files`: the long runs write
and read them; this module knows only the harness's Verilog).
``clear`` goes straight to the array's port.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rvsm.model.infra.errors import ToolError

__all__ = ["CLOCK_NS", "DEFAULT_DEPTH", "HARNESS_TOP", "HARNESS_VERSION",
           "STAMP_BITS", "TAIL", "HarnessLayout", "StateMemories", "StateMemory",
           "clock_inside", "harness_verilog", "state_memories"]

#: Bump when the harness's Verilog changes (part of a harness build's cache key).
HARNESS_VERSION = "5"
#: Module name of the harness (the simulation's top level).
HARNESS_TOP = "rvsm_chunk_harness"
#: Beats per chunk the harness memories hold.
DEFAULT_DEPTH = 8192
#: Idle cycles after a chunk's last beat before its outputs are written: the last
#: output beat is presented in the second cycle after its input beat is taken.
TAIL = 4
#: Clock period (ns) of a harness that makes its own clock (the testbenches' ``CLOCK_NS``).
CLOCK_NS = 10
#: Bits of the cycle stamp stored with each output beat.
STAMP_BITS = 32


@dataclass(frozen=True)
class HarnessLayout:
    """What the harness needs of the array's port map: the top module's name and port
    widths, the spike payload's fields ``{name: (offset, width)}``, and the memory
    ``depth`` (beats per chunk)."""

    top: str
    widths: dict[str, int]
    fields: dict[str, tuple[int, int]]
    depth: int = DEFAULT_DEPTH
    #: Cycles after a chunk's last beat before its outputs are written (a design with a
    #: longer latency than the array's, e.g. the link loopback, needs more).
    tail: int = TAIL
    #: Cycles from one threshold write of ``thr_load`` to the next (1: every cycle).
    thr_every: int = 1

    @classmethod
    def from_ports(cls, ports: dict, depth: int = DEFAULT_DEPTH) -> HarnessLayout:
        """From a loaded ``<top>.ports.json`` (:func:`rvsm.rtl.ports.load_ports_json`)."""
        by_name = {p["name"]: p for p in ports["ports"]}
        need = ("clk", "rst", "clear", "codes_valid", "codes_ready", "codes_payload",
                "spikes_valid", "spikes_payload", "thr_we", "thr_addr", "thr_data")
        missing = [n for n in need if n not in by_name]
        if missing:
            raise ToolError(f"the port map of {ports.get('top')!r} lacks {missing}: not a "
                            "streaming array")
        fields = {f["name"]: (int(f["offset"]), int(f["width"]))
                  for f in by_name["spikes_payload"]["fields"]}
        return cls(str(ports["top"]), {n: int(by_name[n]["width"]) for n in need}, fields,
                   int(depth))

    @property
    def in_bits(self) -> int:
        """Bits of one input beat (``codes_payload``)."""
        return self.widths["codes_payload"]

    @property
    def out_bits(self) -> int:
        """Bits of one output beat (``spikes_payload``)."""
        return self.widths["spikes_payload"]

    @property
    def ports(self) -> list[str]:
        """The harness's own ports (what the testbench touches)."""
        return ["clk", "rst", "clear", "thr_we", "thr_addr", "thr_data", "thr_load",
                "thr_count", "start", "count", "done", "out_count", "stray", "overflow",
                "state_load", "state_dump"]


@dataclass(frozen=True)
class StateMemory:
    """One bank of a state memory of the array: ``kind`` (``"acc"`` or ``"thr"``),
    ``scale``, ``bank``, ``width`` bits x ``depth`` words, and its hierarchical
    ``name`` below the array's instance, as Verilog text."""

    kind: str
    scale: int
    bank: int
    width: int
    depth: int
    name: str

    @property
    def file(self) -> str:
        """Its file name in ``state_in/`` and ``state_out/``."""
        return f"{self.kind}_s{self.scale}.b{self.bank}.hex"


@dataclass(frozen=True)
class StateMemories:
    """The array's state memory banks (in scale, bank order) and the hierarchical name
    of its fresh-frame flag (``fresh_s0``)."""

    banks: tuple[StateMemory, ...]
    fresh: str


_MODULE = re.compile(r"^module\s+(\\\S+|\w+)\s*\((.*?)^endmodule", re.S | re.M)
_BANK = re.compile(r"^\s*reg\s+\[(\d+):0\]\s+(\\\S+|\w+)\s+\[(\d+):(\d+)\];", re.M)
_FRESH = re.compile(r"^\s*reg\s+(\\\S+|\w+)\s*=\s*1'h1;", re.M)


def state_memories(verilog: str, top: str) -> StateMemories:
    """The state memory banks of the streaming array ``top`` in its Verilog: Amaranth's
    (a module ``\\top.acc_s0`` declaring ``reg [W-1:0] b0 [N-1:0]``: name
    ``acc_s0.b0``) or the flat Icarus netlist (``reg ... \\acc_s0.b0  [...]`` in the
    top module: that escaped name). Raises :class:`ToolError` when none is found."""
    banks: list[StateMemory] = []
    fresh = None
    for m in _MODULE.finditer(verilog):
        module, body = m.group(1), m.group(2)
        plain = module.lstrip("\\")
        inside = plain[len(top) + 1:].split(".") if plain.startswith(top + ".") else []
        for b in _BANK.finditer(body):
            width, name, hi, lo = int(b.group(1)) + 1, b.group(2), int(b.group(3)), \
                int(b.group(4))
            path = [*inside, name.lstrip("\\")]
            # the bank's array, named by its module (``acc_s0.b0``) or inside it
            # (``state.acc_s0.b0.mem``, the memory lowered as a cell of its own)
            found = re.fullmatch(r"(?:.*\.)?(acc|thr)_s(\d+)\.b(\d+)(?:\.mem)?",
                                 ".".join(path))
            if not found:
                continue
            text = ".".join(path) if not name.startswith("\\") else name + " "
            banks.append(StateMemory(found.group(1), int(found.group(2)),
                                     int(found.group(3)), width, abs(hi - lo) + 1, text))
        for f in _FRESH.finditer(body):
            if f.group(1).lstrip("\\").endswith("fresh_s0"):
                name = f.group(1)
                fresh = (".".join([*inside, name]) if not name.startswith("\\")
                         else name + " ")
    if not banks or fresh is None:
        raise ToolError(f"no state memories (acc_s*/thr_s* banks, fresh_s0) found in the "
                        f"Verilog of {top!r}: the long-run harness cannot load or dump "
                        "its state")
    banks.sort(key=lambda b: (b.kind, b.scale, b.bank))
    return StateMemories(tuple(banks), fresh)


def clock_inside(sim: str) -> bool:
    """Whether the harness of a ``sim`` build makes its own clock: Icarus only."""
    return sim == "icarus"


def harness_verilog(layout: HarnessLayout, clock_inside: bool = False,
                    state: StateMemories | None = None) -> str:
    """The Verilog text of :data:`HARNESS_TOP` around ``layout.top``; ``clock_inside``:
    ``clk`` is made by the harness (module docstring), not driven from outside;
    ``state``: the banks ``state_load`` / ``state_dump`` reach (none: both do
    nothing)."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", layout.top):
        raise ToolError(f"not a Verilog identifier: {layout.top!r}")
    w = layout.widths
    depth = layout.depth
    abits = max(1, (depth - 1).bit_length())
    ib, ob, sb = layout.in_bits, layout.out_bits, STAMP_BITS
    ta, td = w["thr_addr"], w["thr_data"]
    thr_depth = 1 << ta  # at most one write per address
    tbits = ta
    return f"""// Simulation-only long-run harness around {layout.top}: generated by rvsm
// (sim/cosim/builds/chunk_harness.py). Not for synthesis ($readmemh/$writememh, $dumpvars).
`timescale 1ns/1ps
// verilator coverage_off
module {HARNESS_TOP} (
  {"output reg  clk," if clock_inside else "input  wire clk,"}
  input  wire rst,
  input  wire clear,
  input  wire thr_we,
  input  wire [{w['thr_addr'] - 1}:0] thr_addr,
  input  wire [{w['thr_data'] - 1}:0] thr_data,
  input  wire thr_load,
  input  wire [31:0] thr_count,
  input  wire start,
  input  wire [31:0] count,
  input  wire state_load,
  input  wire state_dump,
  output reg  done,
  output reg  [31:0] out_count,
  output reg  [31:0] stray,
  output reg  overflow
);
  localparam DEPTH = {depth};
  reg [{ib - 1}:0] in_mem [0:DEPTH-1];
  reg [{ob + sb - 1}:0] out_mem [0:DEPTH-1];
  reg [{ta + td - 1}:0] thr_mem [0:{thr_depth - 1}];
  reg [8*1024-1:0] in_file, out_file, dump_file, thr_file;
  reg [63:0] cycle, dump_from, dump_to;
  reg dumping;
  reg running;
  reg [31:0] taken;
  reg [31:0] tail;
  reg thr_loading;
  reg [31:0] thr_taken;
  reg [15:0] thr_gap;
  wire thr_fire = thr_loading && thr_gap == 16'd0;
  reg state_load_now, state_dump_now;
  wire [{ta + td - 1}:0] thr_word = thr_mem[thr_taken[{tbits - 1}:0]];
  wire codes_ready;
  wire spikes_valid;
  wire [{ob - 1}:0] spikes_payload;
  wire codes_valid = running && (taken < count);
  wire [{ib - 1}:0] codes_payload = in_mem[taken[{abits - 1}:0]];

  {layout.top} dut (
    .clk(clk), .rst(rst), .clear(clear),
    .codes_valid(codes_valid), .codes_ready(codes_ready), .codes_payload(codes_payload),
    .spikes_valid(spikes_valid), .spikes_payload(spikes_payload),
    .thr_we(thr_fire | thr_we),
    .thr_addr(thr_loading ? thr_word[{ta + td - 1}:{td}] : thr_addr),
    .thr_data(thr_loading ? thr_word[{td - 1}:0] : thr_data)
  );

{_CLOCK.format(half=CLOCK_NS // 2, period=CLOCK_NS) if clock_inside else ""}  initial begin
    if (!$value$plusargs("rvsm_chunk_in=%s", in_file)) in_file = "chunk_in.hex";
    if (!$value$plusargs("rvsm_chunk_out=%s", out_file)) out_file = "chunk_out.hex";
    if (!$value$plusargs("rvsm_thr_in=%s", thr_file)) thr_file = "thresholds.hex";
    dumping = 0;
    if (!$value$plusargs("rvsm_dump_file=%s", dump_file)) dump_file = 0;
    if (!$value$plusargs("rvsm_dump_from=%d", dump_from)) dump_from = 64'hffffffffffffffff;
    if (!$value$plusargs("rvsm_dump_to=%d", dump_to)) dump_to = 0;
    cycle = 0;
    running = 0;
    done = 0;
    taken = 0;
    tail = 0;
    thr_loading = 0;
    thr_taken = 0;
    thr_gap = 0;
    state_load_now = 0;
    state_dump_now = 0;
    out_count = 0;
    stray = 0;
    overflow = 0;
  end

{_state_block(state)}
  always @(posedge clk) begin
    cycle <= cycle + 64'd1;
    state_load_now <= state_load && !running;
    state_dump_now <= state_dump && !running;
    if (dump_file != 0 && cycle == dump_from) begin
      $dumpfile(dump_file);
      $dumpvars(0, dut);
      dumping <= 1;
    end
    if (dumping && cycle == dump_to + 64'd1) begin
      $dumpoff;
      $dumpflush;
      dumping <= 0;
    end
    if (rst) begin
      running <= 0;
      done <= 0;
      taken <= 0;
      out_count <= 0;
      stray <= 0;
      overflow <= 0;
      thr_loading <= 0;
    end else begin
      if (thr_loading && thr_gap != 16'd0)
        thr_gap <= thr_gap - 16'd1;
      else if (thr_loading) begin
        if (thr_taken + 32'd1 == thr_count) begin
          thr_loading <= 0;
          done <= 1;
        end
        thr_taken <= thr_taken + 32'd1;
        thr_gap <= 16'd{layout.thr_every - 1};
      end else if (thr_load && !running) begin
        $readmemh(thr_file, thr_mem, 0, thr_count - 32'd1);
        thr_loading <= 1;
        thr_taken <= 0;
        thr_gap <= 0;
        done <= 0;
      end
      if (spikes_valid) begin
        if (!running)
          stray <= stray + 32'd1;
        else if (out_count < DEPTH) begin
          out_mem[out_count[{abits - 1}:0]] <= {{cycle[{sb - 1}:0], spikes_payload}};
          out_count <= out_count + 32'd1;
        end else
          overflow <= 1;
      end
      if (start && !running) begin
        $readmemh(in_file, in_mem, 0, count - 32'd1);
        running <= 1;
        done <= 0;
        taken <= 0;
        tail <= 0;
        out_count <= 0;
      end else if (running) begin
        if (codes_valid && codes_ready)
          taken <= taken + 32'd1;
        else if (taken == count) begin
          if (tail == {layout.tail}) begin
            if (out_count != 0)
              $writememh(out_file, out_mem, 0, out_count - 32'd1);
            running <= 0;
            done <= 1;
          end else
            tail <= tail + 32'd1;
        end
      end
    end
  end
endmodule
// verilator coverage_on
"""


def _state_block(state: StateMemories | None) -> str:
    """The falling-edge block loading and dumping the array's state (module docstring)."""
    if state is None:
        return "  // no state memories: state_load and state_dump do nothing"
    load = "".join(f'      $readmemh("state_in/{b.file}", dut.{b.name}, 0, {b.depth - 1});\n'
                   for b in state.banks)
    dump = "".join(f'      $writememh("state_out/{b.file}", dut.{b.name}, 0, {b.depth - 1});\n'
                   for b in state.banks)
    return f"""  // The array's state, reached by hierarchical names (simulation only).
  always @(negedge clk) begin
    if (state_load_now) begin
{load}      dut.{state.fresh} = 1'b0;
    end
    if (state_dump_now) begin
{dump}    end
  end
"""


_CLOCK = """  // The clock, made here (no call into Python per edge): rising edges every {period} ns
  // from time 0, as cocotb's Clock drives them.
  // (From x straight to 1, after the time-0 processes have started: a rising edge at 0
  // that every clocked block sees, and no falling edge there.)
  initial begin
    #0 clk = 1'b1;
    forever #{half} clk = ~clk;
  end

"""

