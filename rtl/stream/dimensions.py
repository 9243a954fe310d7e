"""Sizes and timing of a streaming array, in pure Python: :class:`StreamGeometry`.

L is the kernel radius (:func:`~rvsm.model.kernels.geometry.kernel_radius`), E =
``ceil(L / P)`` the column groups a window reaches either side, G = ``W / P`` the beats
per row; the pipeline depth comes from planning the receptive sums
(:class:`~rvsm.rtl.stream.pipelined_sum.Pipeline` without a module), so every timing
property is a named value, never a number in a test. The component is
:class:`~rvsm.rtl.stream.array.RvsmStreamArray`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from amaranth.lib import data

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.geometry import kernel_radius
from rvsm.rtl.interfaces import ThresholdWriteSignature
from rvsm.rtl.receptive_sum import sum_width
from rvsm.rtl.stream.pipelined_sum import Pipeline, Timed, orbit_terms, weighted_orbits
from rvsm.rtl.stream.schedule import StreamSchedule, pack_lanes
from rvsm.rtl.stream.signatures import (
    spike_beat_layout,
    threshold_word_bits,
    threshold_write_signature,
    top_threshold_word,
)
from rvsm.rtl.threshold_storage import shared_threshold_values

__all__ = ["StreamGeometry"]


class StreamGeometry:
    """Sizes and timing of a stream array: pure Python, nothing to elaborate.

    ``RvsmStreamArray(contract, lanes).geometry``, or build one directly when only the
    schedule or the named timing properties are needed (e.g. by a testbench).
    """

    #: Adder levels between pipeline registers in the receptive-sum trees (1: one carry
    #: chain per register stage, the ECP5 timing at 150 MHz; 2 placed P = 1 at 145 MHz,
    #: two chained adders being the critical path).
    LEVELS_PER_STAGE = 1
    #: Default largest number of words in one bank of a state memory (one ECP5 DP16KD
    #: holds 1024 words of up to 18 bits; wider words use several in parallel).
    BANK_WORDS = 1024
    #: Stages from the sums' register to the output register: add, compare, reset.
    TAIL_STAGES = 3
    #: Registers between the input ports and the datapath (accepted beat, clear).
    INPUT_STAGES = 1
    #: Advance edges from a state-memory read address to its data: the block-RAM read
    #: latch, the bank's output register (the DP16KD output register in the ECP5 build)
    #: and the registered bank multiplexer
    #: (:class:`~rvsm.rtl.stream.banked_memory.BankedMemory` ``read_stages``).
    READ_STAGES = 3

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 bank_words: int = BANK_WORDS):
        c = contract
        if bank_words < 1 or bank_words & (bank_words - 1):
            raise RvsmError(f"bank_words must be a power of two, got {bank_words}")
        self.bank_words = int(bank_words)
        if isinstance(lanes, bool) or not isinstance(lanes, (int, np.integer)) \
                or lanes < 1 or c.width % lanes:
            asked = int(lanes) if isinstance(lanes, (int, np.integer)) else 1
            near = sorted(sorted((p for p in range(1, c.width + 1) if c.width % p == 0),
                                 key=lambda p: abs(p - asked))[:6])
            raise RvsmError(f"lanes must be a positive divisor of the width {c.width}, "
                            f"got {lanes}; the divisors near it: "
                            f"{', '.join(map(str, near))}")
        self.contract = c
        self.lanes = int(lanes)
        self.groups = c.width // self.lanes
        self.radius = kernel_radius(c.weight_arrays)
        self.edge_groups = -(-self.radius // self.lanes)
        self.orbits = weighted_orbits(c.weights)
        self.beats_per_frame = c.height * self.groups
        self.sum_stage = self.build_sums(Pipeline(None, None, self.LEVELS_PER_STAGE), None)[1]
        if self.beats_per_frame <= self.rmw_depth:
            raise RvsmError(
                f"the stream array needs more than {self.rmw_depth} beats per frame (its "
                f"read-modify-write depth); {c.height}x{c.width} at {lanes} lane(s) has "
                f"{self.beats_per_frame}: use fewer lanes")

    @property
    def shared_thresholds(self) -> bool:
        """One threshold register per scale (``threshold.storage = "shared"``) instead of
        the threshold memories."""
        return self.contract.shared_thresholds is not None

    @property
    def threshold_bus(self) -> ThresholdWriteSignature:
        """The threshold-write bus (:func:`threshold_write_signature`): one memory word
        of ``P`` thresholds per write, or with shared thresholds one scale's threshold."""
        c = self.contract
        return threshold_write_signature(c.num_scales, self.beats_per_frame, self.lanes,
                                         c.threshold_bits, self.shared_thresholds)

    @property
    def threshold_words(self) -> int:
        """Threshold-bus words per scale: ``H*G`` memory words, or 1 (the register)."""
        return 1 if self.shared_thresholds else self.beats_per_frame

    @property
    def threshold_data_bits(self) -> int:
        """Bits of one threshold write: ``P*(W-1)``, or ``W-1`` with shared thresholds."""
        return self.contract.threshold_bits * (1 if self.shared_thresholds else self.lanes)

    def threshold_reset_data(self, scale: int) -> int:
        """What a reset restores in scale ``scale``'s words: every threshold at the top
        rail ``2**(W-1)-1`` (no spike until loaded), or with shared thresholds the
        register's configuration value, the contract's nominal threshold."""
        c = self.contract
        if self.shared_thresholds:
            return c.shared_thresholds[scale]
        return top_threshold_word(c.threshold_bits, self.lanes)

    def threshold_address(self, scale: int, word: int) -> int:
        """The bus address of memory word ``word`` (``y*G + g``) of scale ``scale``:
        ``(s << word_bits) | word``; with shared thresholds ``s`` (``word`` unused)."""
        if self.shared_thresholds:
            return int(scale)
        return int(scale) << threshold_word_bits(self.beats_per_frame) | int(word)

    def threshold_data(self, values: np.ndarray) -> int:
        """The bus ``data`` writing thresholds ``values (P,)`` to one word: ``P``
        thresholds packed, lane 0 lowest; with shared thresholds the one threshold (the
        values must be equal)."""
        values = np.asarray(values, dtype=np.int64).reshape(-1)
        if self.shared_thresholds:
            return shared_threshold_values(self.contract, values[None])[0]
        return pack_lanes(values[None], self.contract.threshold_bits)[0]

    def words_written(self, word: int) -> int | slice:
        """The words (index into ``(H*G,)``) a write addressed to ``word`` changes: that
        word, or with shared thresholds every word of the scale (one register)."""
        return slice(None) if self.shared_thresholds else int(word)

    def threshold_writes(self, thresholds: np.ndarray) -> list[tuple[int, int]]:
        """``(addr, data)`` of every write loading thresholds ``(S, H, W)``: scale by
        scale, word ``y*G + g`` in order, ``P`` thresholds per word; with shared
        thresholds one write per scale (:func:`~rvsm.rtl.threshold_storage.
        shared_threshold_values`: one value per scale, or refused)."""
        c = self.contract
        if self.shared_thresholds:
            return list(enumerate(shared_threshold_values(c, thresholds)))
        words = self.schedule.threshold_words(np.asarray(thresholds, dtype=np.int64))
        packed = pack_lanes(words.reshape(-1, self.lanes), c.threshold_bits)
        n = self.beats_per_frame
        return [(self.threshold_address(k // n, k % n), word)
                for k, word in enumerate(packed)]

    @property
    def window_lag(self) -> int:
        """Input beats after position ``p`` until its window is complete: ``L*G + E``."""
        return self.radius * self.groups + self.edge_groups

    @property
    def pipeline_depth(self) -> int:
        """Registered stages from the window register to the output register."""
        return self.sum_stage + self.TAIL_STAGES

    @property
    def latency(self) -> int:
        """Clock cycles from the edge accepting beat ``p + window_lag`` to the edge
        presenting ``p``'s output, when beats are back to back."""
        return self.INPUT_STAGES + self.pipeline_depth

    @property
    def lag(self) -> int:
        """Output ``p`` is released by input beat ``p + lag`` (presented in the second
        cycle after that beat's acceptance)."""
        return self.window_lag + self.pipeline_depth

    @property
    def pixel_to_spike(self) -> int:
        """Clock cycles from the edge accepting a pixel's beat ``p`` to the edge presenting
        its spikes, beats back to back: ``window_lag + latency`` (``lag + 1``)."""
        return self.window_lag + self.latency

    @property
    def rmw_depth(self) -> int:
        """Beats from an accumulator read (address sampled) to its write-back."""
        return self.TAIL_STAGES + self.READ_STAGES - 1

    @property
    def rmw_guard_bits(self) -> int:
        """Low address bits that tell an accumulator read from the write at its edge.

        The read of position ``p`` meets the write-back of ``p - rmw_depth``, so the
        addresses differ by ``rmw_depth`` or ``rmw_depth - beats_per_frame``: the
        smallest ``k`` for which ``2**k`` divides neither (all address bits at most).
        """
        def twos(v: int) -> int:
            return (v & -v).bit_length() - 1

        d, n = self.rmw_depth, self.beats_per_frame
        return min(1 + max(twos(d), twos(n - d)), max(1, (n - 1).bit_length()))

    @property
    def threshold_lag(self) -> int:
        """Position ``p`` reads its thresholds at the edge after the one accepting input
        beat ``p + threshold_lag``."""
        return self.window_lag + self.read_stage + 1

    @property
    def read_stage(self) -> int:
        """The pipeline stage whose position addresses the state memories: the sums'
        stage less :attr:`READ_STAGES`, so the data arrives with the sums."""
        return self.sum_stage - self.READ_STAGES

    @property
    def bank_sizes(self) -> list[int]:
        """Words per bank of each state memory (every bank but the last is full)."""
        n, b = self.beats_per_frame, self.bank_words
        return [min(b, n - i) for i in range(0, n, b)]

    @property
    def state_bits(self) -> dict[str, int]:
        """Memory bits: ``accumulators`` (``S*H*W*A``), ``thresholds`` (``S*H*W*(A-1)``;
        0 with shared thresholds, whose ``S*(A-1)`` bits are registers), ``line_buffer``
        (``2L*W*N``); the sensor-level account of the same bits, with the devices that
        hold them, is ``rtl/fpga/camera.py``'s ``StateMemory``."""
        c = self.contract
        accumulators = c.num_scales * c.height * c.width
        return {"accumulators": accumulators * c.accumulator_bits,
                "thresholds": 0 if c.shared_thresholds is not None
                else accumulators * c.threshold_bits,
                "line_buffer": 2 * self.radius * c.width * c.adc_bits}

    @property
    def schedule(self) -> StreamSchedule:
        """The numpy model of this array's beat schedule."""
        c = self.contract
        return StreamSchedule(c.height, c.width, self.lanes, self.lag, self.threshold_lag)

    @property
    def spike_layout(self) -> data.StructLayout:
        """Layout of the output payload (:func:`spike_beat_layout`)."""
        c = self.contract
        return spike_beat_layout(c.num_scales, self.lanes, c.height, self.groups)

    def timing(self) -> dict[str, int]:
        """The named timing properties, as a dict (for port maps and reports)."""
        return {k: getattr(self, k) for k in (
            "lanes", "groups", "radius", "window_lag", "pipeline_depth", "latency", "lag",
            "rmw_depth", "threshold_lag", "beats_per_frame")}

    def sum_bits(self, scale: int) -> int:
        """Signed width of scale ``scale``'s exact weighted sum."""
        return sum_width(*self.contract.sum_range(scale))

    def window_cells(self) -> list[tuple[int, int]]:
        """Window cells ``(d, j)`` (row 0..2L, column 0..P+2L-1) some tap reads."""
        r = self.radius
        return sorted({(r + dy, r + i + dx) for i in range(self.lanes)
                       for o in self.orbits for dy, dx in o.offsets})

    def build_sums(self, pipe: Pipeline, window: Mapping[tuple[int, int], Timed] | None
                   ) -> tuple[list[list[Timed]], int]:
        """Per lane, per scale the weighted sum; and the stage they are all registered at.

        ``window`` maps cells to stage-1 values; ``None`` plans (stage numbers only).
        """
        c, r, n = self.contract, self.radius, self.contract.adc_bits
        if window is None:
            window = {cell: pipe.timed(None, 1) for cell in self.window_cells()}
        sums = []
        for i in range(self.lanes):
            orbit_sums = []
            for o in self.orbits:
                terms = [(1, window[(r + dy, r + i + dx)], 0) for dy, dx in o.offsets]
                width = n + (len(terms) - 1).bit_length()
                orbit_sums.append(pipe.settle(pipe.sum(terms, width)))
            sums.append([pipe.settle(pipe.sum(orbit_terms(orbit_sums, self.orbits, s),
                                              self.sum_bits(s)))
                         for s in range(c.num_scales)])
        stage = max([self.READ_STAGES] + [t.stage for lane in sums for t in lane])
        return sums, stage

    def stage_q_sums(self, pipe: Pipeline, window: Mapping[tuple[int, int], Timed]
                     ) -> tuple[list[list[Timed]], int]:
        """:meth:`build_sums` with every sum delayed to the common stage Q
        (:attr:`sum_stage`): ``(sums[lane][scale], Q)``, what the array adds to its
        accumulators (the formal lemma ``sums`` checks this very circuit)."""
        sums, stage_q = self.build_sums(pipe, window)
        if stage_q != self.sum_stage:
            raise AssertionError("planned and built sum stages differ")
        return [[pipe.at(t, stage_q) for t in lane] for lane in sums], stage_q
