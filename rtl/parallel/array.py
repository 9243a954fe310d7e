"""The fully parallel RVSM pixel array, built from one :class:`ArrayContract`.

Architecture (one clock domain ``sync``, synchronous reset ``rst``)::

    codes[H*W*N] --> per (scale, pixel): receptive weighted sum (constant shift-and-add,
                     :mod:`rvsm.rtl.receptive_sum`) --> PixelCell (shift, saturate,
                     compare, fire, reset; threshold register) --> spike_pos / spike_neg
    cfg (we/addr/data) --> address decode --> one cell's threshold register

Bit ordering of the flat ports (all little-endian, index 0 = LSB):

* ``codes``: pixel ``(y, x)`` at bits ``[(y*W + x)*N +: N]`` (unsigned ADC code);
* ``spike_pos`` / ``spike_neg``: accumulator ``a = (s*H + y)*W + x`` at bit ``a``;
* ``cfg.addr``: the same accumulator index ``a``; ``cfg.data`` the threshold
  (``1 .. 2**(W-1)-1``), written when ``cfg.we`` is high at a clock edge. With shared
  thresholds (``threshold.storage = "shared"``) the cells have none of their own: one
  register per scale (reset to the contract's nominal threshold), ``cfg.addr`` the
  scale ``s``. ``cfg`` is the
  threshold-write bus (:class:`~rvsm.rtl.interfaces.ThresholdWriteSignature`); in the
  Verilog its ports are ``cfg_we``, ``cfg_addr``, ``cfg_data`` (:mod:`rvsm.rtl.ports`).

Timing: ``codes`` are sampled at a rising edge where ``strobe`` is high (one contract
step per strobe; strobes may be back to back); the spikes of that step are on
``spike_pos``/``spike_neg`` with ``valid`` high :attr:`RvsmArray.latency` cycles later
and hold until the next strobe. ``clear`` (synchronous, priority over ``strobe``) zeroes
every accumulator and spike but keeps the thresholds: a restart of the stream.

The bit-accurate model of this component is :meth:`ArrayContract.run`; it is driven in
``amaranth.sim`` by :func:`rvsm.rtl.parallel.drive.simulate`.
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Module, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import index_bits, unsigned_max
from rvsm.rtl.interfaces import ThresholdWriteSignature
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.parallel.pixel_cell import PixelCell
from rvsm.rtl.receptive_sum import sum_width, weighted_sum
from rvsm.rtl.threshold_storage import indexed_threshold_writes

__all__ = ["RvsmArray", "accumulator_index", "receptive_taps"]


def receptive_taps(contract: ArrayContract, scale: int, row: int, col: int
                   ) -> list[tuple[tuple[int, int], int]]:
    """The taps of accumulator ``(scale, row, col)``'s weighted sum, in the order its
    adder network takes them (kernel rows, then columns): ``((y, x), weight)`` for every
    non-zero weight over a pixel inside the array (padding drops the rest)."""
    kernel = contract.weights[scale]
    half = len(kernel) // 2
    h, w = contract.height, contract.width
    return [((row + di - half, col + dj - half), wt)
            for di, krow in enumerate(kernel) for dj, wt in enumerate(krow)
            if wt and 0 <= row + di - half < h and 0 <= col + dj - half < w]


def accumulator_index(contract: ArrayContract, scale: int, row: int, col: int) -> int:
    """Flat index of accumulator ``(scale, row, col)``: ``(scale*H + row)*W + col``."""
    return (scale * contract.height + row) * contract.width + col


class RvsmArray(wiring.Component):
    """``S x H x W`` accumulators over an ``H x W`` ADC-code input, from a contract.

    Ports: ``codes`` In(H*W*N), ``strobe`` In(1), ``clear`` In(1), ``cfg``
    In(ThresholdWriteSignature(W-1, addr_bits)), ``spike_pos`` Out(S*H*W), ``spike_neg``
    Out(S*H*W), ``valid`` Out(1). See the module docstring for ordering;
    :meth:`port_docs` describes each Verilog port.
    """

    #: Clock cycles from the strobe edge sampling ``codes`` to valid spike outputs.
    LATENCY = PixelCell.LATENCY

    def __init__(self, contract: ArrayContract, mutation: str | None = None):
        self.contract = contract
        #: A deliberate bug (:mod:`rvsm.rtl.mutations`) or None (the shipped logic).
        self.mutation = check_mutation(mutation, "parallel")
        self.num_accumulators = contract.num_scales * contract.height * contract.width
        self.addr_bits = index_bits(self.num_accumulators)
        #: The cells by accumulator index, filled when elaborated (formal harnesses
        #: observe their ``acc`` and ``threshold``).
        self.cells: dict[int, PixelCell] = {}
        super().__init__(self.interface(contract))

    @staticmethod
    def threshold_writes(contract: ArrayContract, thresholds: np.ndarray
                         ) -> list[tuple[int, int]]:
        """``(cfg_addr, cfg_data)`` of every write loading thresholds ``(S, H, W)``: one
        per accumulator (index ``a``), or with shared thresholds one per scale
        (:func:`~rvsm.rtl.threshold_storage.indexed_threshold_writes`)."""
        return indexed_threshold_writes(contract, thresholds)

    @staticmethod
    def interface(contract: ArrayContract) -> wiring.Signature:
        """The array's signature for ``contract`` (no component needed)."""
        c = contract
        n_acc = c.num_scales * c.height * c.width
        targets = c.num_scales if c.shared_thresholds is not None else n_acc
        return wiring.Signature({
            "codes": In(unsigned(c.height * c.width * c.adc_bits)),
            "strobe": In(1),
            "clear": In(1),
            "cfg": In(ThresholdWriteSignature(c.threshold_bits, index_bits(targets))),
            "spike_pos": Out(unsigned(n_acc)),
            "spike_neg": Out(unsigned(n_acc)),
            "valid": Out(1),
        })

    @property
    def latency(self) -> int:
        """Clock cycles from the strobe edge sampling ``codes`` to valid spike outputs."""
        return self.LATENCY

    @property
    def pixel_to_spike(self) -> int:
        """Clock cycles from the edge sampling a pixel's code to its spikes: every pixel
        of a step is strobed at once, so :attr:`latency`."""
        return self.latency

    @classmethod
    def port_docs(cls, contract: ArrayContract) -> dict[str, str]:
        """Meaning of every Verilog port (names as :func:`rvsm.rtl.ports.port_map`)."""
        c = contract
        n_acc = c.num_scales * c.height * c.width
        top = unsigned_max(c.threshold_bits)
        shared = c.shared_thresholds
        cfg = {"cfg_we": "threshold write enable",
               "cfg_addr": f"accumulator index (s*{c.height}+y)*{c.width}+x, 0..{n_acc - 1}",
               "cfg_data": f"threshold, 1..{top}"} if shared is None else {
            "cfg_we": "threshold write enable (one scale's register)",
            "cfg_addr": f"scale s, 0..{c.num_scales - 1} (threshold.storage = shared)",
            "cfg_data": f"the scale's threshold, 1..{top}"}
        return {
            "clk": "clock (rising edge)",
            "rst": "synchronous reset: accumulators and spikes to 0, thresholds to "
                   + (f"{top}" if shared is None else ", ".join(map(str, shared))),
            "codes": f"ADC codes, pixel (y, x) at bits [(y*{c.width}+x)*{c.adc_bits} +: "
                     f"{c.adc_bits}]",
            "strobe": "sample strobe: one contract step per rising edge with strobe=1",
            "clear": "synchronous clear of accumulators and spikes (thresholds kept); "
                     "priority over strobe",
            **cfg,
            "spike_pos": "+1 spikes, accumulator (s*H+y)*W+x at that bit",
            "spike_neg": "-1 spikes, same ordering (always 0 for unsigned models)",
            "valid": f"spikes of a strobed step are valid (latency {cls.LATENCY} cycle(s))",
        }

    def elaborate(self, platform: object) -> Module:
        """Weighted sums, cells, threshold address decode, valid pipeline."""
        m = Module()
        c = self.contract
        h, w, n = c.height, c.width, c.adc_bits
        pix = [[self.codes[(y * w + x) * n:(y * w + x + 1) * n] for x in range(w)]
               for y in range(h)]

        valid_pipe = [Signal(name=f"valid_d{i}") for i in range(self.latency)]
        go = self.strobe & ~self.clear
        for i, stage in enumerate(valid_pipe):
            m.d.sync += stage.eq(go if i == 0 else valid_pipe[i - 1])
        m.d.comb += self.valid.eq(valid_pipe[-1])

        shared = c.shared_thresholds is not None
        registers = [Signal(unsigned(c.threshold_bits), name=f"thr_s{s}", init=t)
                     for s, t in enumerate(c.shared_thresholds or ())]
        for s, register in enumerate(registers):  # threshold.storage = "shared"
            with m.If(self.cfg.we & (self.cfg.addr == s)):
                m.d.sync += register.eq(self.cfg.data)
        for s in range(c.num_scales):
            lo, hi = c.sum_range(s)
            for y in range(h):
                for x in range(w):
                    pixels_weights = receptive_taps(c, s, y, x)
                    taps = [pix[yy][xx] for (yy, xx), _ in pixels_weights]
                    wts = [wt for _, wt in pixels_weights]
                    a = accumulator_index(c, s, y, x)
                    cell = PixelCell(sum_width(lo, hi), c.shift, c.accumulator_bits,
                                     c.signed, c.reset, self.mutation,
                                     c.kind.output, shared_threshold=shared)
                    self.cells[a] = cell
                    m.submodules[f"cell_s{s}_y{y}_x{x}"] = cell
                    m.d.comb += [
                        cell.sum_in.eq(weighted_sum(taps, wts, lo, hi)),
                        cell.strobe.eq(self.strobe),
                        cell.clear.eq(self.clear),
                        *([cell.threshold_in.eq(registers[s])] if shared else
                          [cell.thr.we.eq(self.cfg.we & (self.cfg.addr == a)),
                           cell.thr.data.eq(self.cfg.data)]),
                        self.spike_pos[a].eq(cell.spike_pos),
                        self.spike_neg[a].eq(cell.spike_neg),
                    ]
        return m
