"""The twin's work in the long-run twin process (:mod:`.chunk_twin`): every chunk's
input files made ahead of the simulator and every output file checked against the
twin, in the order the beats were simulated (:class:`ChunkTwin`); the harness's output
words as beats, cycle stamps and unknown flags (:func:`decode_beats`)."""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from rvsm.model.fixed.stimulus_chunks import open_stimulus_chunks
from rvsm.rtl.capabilities import BeatStream
from rvsm.rtl.ports import load_ports_json
from rvsm.sim.cosim.builds.chunk_harness import STAMP_BITS, HarnessLayout
from rvsm.sim.cosim.long_runs.chunk_files import (
    decode_output_beats,
    encode_input_beats,
    encode_threshold_writes,
)
from rvsm.sim.cosim.long_runs.segment_state import SegmentState
from rvsm.sim.cosim.testbenches.tb_common import beat_stream, stream_geometry

__all__ = ["ChunkTwin", "decode_beats"]


def decode_beats(text: bytes, layout: HarnessLayout, scales: int, lanes: int,
                 beats: BeatStream) -> tuple[object, np.ndarray, np.ndarray]:
    """An output file's text as ``(output beats, cycles (K,), unknown (K,) bool)``, the
    beats of ``beats`` (:attr:`~rvsm.rtl.capabilities.BeatStream.output_beats`)."""
    bits, unknown = decode_output_beats(text, layout.out_bits + STAMP_BITS)
    fields = layout.fields
    cycles = _bits_value(bits, layout.out_bits, STAMP_BITS)
    npos = scales * lanes
    po, _ = fields["pos"]
    ne, _ = fields["neg"]
    spikes = (bits[:, po:po + npos].astype(np.int8)
              - bits[:, ne:ne + npos].astype(np.int8)).reshape(-1, scales, lanes)
    got = beats.output_beats(_bits_value(bits, *fields["row"]),
                             _bits_value(bits, *fields["group"]),
                             _bits_value(bits, *fields["last"]).astype(bool), spikes)
    return got, cycles, unknown


def _bits_value(bits: np.ndarray, offset: int, width: int) -> np.ndarray:
    """Columns ``[offset, offset + width)`` of little-endian bit rows as integers."""
    cols = bits[:, offset:offset + width].astype(np.int64)
    return cols @ (np.int64(1) << np.arange(width, dtype=np.int64))


class ChunkTwin:
    """The twin's state for one run: the chunks, the checker and the timings."""

    def __init__(self, cfg: dict):
        self.t_start = time.time()
        self.dir = Path(cfg["dir"])
        self.stop_on_mismatch = bool(cfg["stop_on_mismatch"])
        source = open_stimulus_chunks(cfg["source"])
        ports = load_ports_json(cfg["ports"])
        self.contract = c = source.contract
        self.beats = beats = beat_stream(ports)
        self.geo = geo = stream_geometry(c, ports)
        self.sched = geo.schedule
        self.layout = HarnessLayout.from_ports(ports, int(cfg["depth"]))
        self._encode_beats = lambda beats: encode_input_beats(beats, c.adc_bits,
                                                              self.layout.in_bits)
        self.checker = beats.checker(self.sched)
        self.border = beats.border_coverage(c, geo.lanes)
        segment = cfg.get("segment")
        self.state: SegmentState | None = None
        if segment is None:
            self.chunks: Iterator = source.chunks(int(cfg["chunk_steps"]))
        else:  # a segment of a sharded run: the state at its start goes to the RTL
            t0, t1 = (int(t) for t in segment)
            chunks = source.chunks(int(cfg["chunk_steps"]), t0, t1)
            t = time.perf_counter()
            first = next(chunks)
            self.seconds_fast_forward = time.perf_counter() - t
            self.chunks = itertools.chain([first], chunks)
            self.checker.restart(t0)
            self.state = SegmentState(source, geo, t0, t1)
            self.state.write_start(self.dir / "state_in")
        self.num_steps = source.num_steps
        flush = np.zeros((self.sched.lag, geo.lanes), dtype=np.uint16)
        writes = beats.threshold_writes(geo, source.thresholds)
        (self.dir / "thresholds.hex").write_bytes(encode_threshold_writes(
            writes, self.layout.widths["thr_addr"], self.layout.widths["thr_data"]))
        self.setup = {"thresholds": len(writes), "state": self.state is not None,
                      "num_steps": source.num_steps, "lanes": geo.lanes,
                      "flush": [(n, self._encode_beats(b)) for n, b in self._parts(flush)]}
        self.expected: dict[int, np.ndarray] = {}
        self.files: dict[int, list[str]] = {}  # input files of chunks not yet taken
        self.produced = self.taken = 0
        self.exhausted = False
        self.failed_at: int | None = None
        self.expected_spikes = 0
        self.seconds = {"twin": 0.0, "encode": 0.0, "decode": 0.0, "check": 0.0,
                        "idle": 0.0}
        self.first_chunk_at: float | None = None

    def _parts(self, beats: np.ndarray) -> list[tuple[int, np.ndarray]]:
        d = self.layout.depth
        return [(min(d, beats.shape[0] - k0), beats[k0:k0 + d])
                for k0 in range(0, beats.shape[0], d)]

    def produce(self) -> tuple:
        """The next chunk's message (its input files written), or ``("end",)``."""
        t = time.perf_counter()
        chunk = next(self.chunks, None)
        tb = time.perf_counter()
        self.seconds["twin"] += tb - t
        if chunk is None:
            self.exhausted = True
            return ("end",)
        k = self.produced
        parts = []
        for j, (n, beats) in enumerate(self._parts(self.sched.frame_beats(chunk.codes))):
            path = self.dir / f"chunk_in.{k}.{j}.hex"
            path.write_bytes(self._encode_beats(beats))
            parts.append((n, str(path)))
        self.seconds["encode"] += time.perf_counter() - tb
        self.expected[k] = chunk.spikes
        self.files[k] = [path for _, path in parts]
        self.produced += 1
        if self.first_chunk_at is None:
            self.first_chunk_at = time.time() - self.t_start
        return ("chunk", k, chunk.t0, chunk.num_steps, chunk.clear, parts)

    def handle(self, msg: tuple) -> tuple | None:
        """One message of the testbench; the reply to send, if any."""
        kind = msg[0]
        if kind == "expect":
            k = int(msg[1])
            self.taken = k + 1
            spikes = self.expected.pop(k)
            del self.files[k]
            if self.failed_at is None:
                self.checker.expect(spikes)
                self.border.update(spikes)
                self.expected_spikes += int(np.count_nonzero(spikes))
            return None
        if kind == "restart":
            if self.failed_at is None:
                self.checker.restart(int(msg[1]))
            return None
        if kind == "check":
            self._check(msg[1], int(msg[2]))
            return ("checked",)
        if kind == "chunk_end":
            if self.stop_on_mismatch and self.checker.mismatches and self.failed_at is None:
                self.failed_at = int(msg[1])
                return ("failed", self.failed_at)
            return None
        raise RuntimeError(f"unknown message from the testbench: {kind!r}")

    def _check(self, path: str | None, n_out: int) -> None:
        t = time.perf_counter()
        if path is None:
            text = b""
        else:
            p = Path(path)
            text = p.read_bytes()
            p.unlink()
        if self.failed_at is not None:
            return
        got, cycles, unknown = decode_beats(text, self.layout, self.contract.num_scales,
                                            self.geo.lanes, self.beats)
        tc = time.perf_counter()
        if got.spikes.shape[0] != n_out:
            raise RuntimeError(f"harness wrote {got.spikes.shape[0]} output beats, counted "
                               f"{n_out}")
        first = self.checker.beats
        self.checker.receive(got, cycles)
        if unknown.any():
            k = int(np.flatnonzero(unknown)[0])
            self.checker.mismatches += int(unknown.sum())
            self.checker.listed.append({"beat": first + k, "cycle": int(cycles[k]),
                                        "error": f"X/Z in {int(unknown.sum())} output "
                                        "beat(s)"})
        self.seconds["decode"] += tc - t
        self.seconds["check"] += time.perf_counter() - tc

    def result(self, ended: bool, steps_done: int, dumped: bool = False) -> dict:
        """The checker's verdict and the twin's figures; ``dumped``: the RTL's state at
        the segment's end is in ``state_out/``, compared word for word with the twin's
        (``boundary``)."""
        for paths in self.files.values():  # made ahead of a run stopped early
            for path in paths:
                Path(path).unlink(missing_ok=True)
        c = self.contract
        finished = ended and self.failed_at is None
        r = {"result": self.checker.result(finished=finished),
             "expected_spikes": self.expected_spikes, "lane_coverage": self.border.bins(),
             "beats_received": self.checker.beats,
             "accumulators": c.num_scales * c.height * c.width, "seconds": self.seconds,
             "first_chunk_at": self.first_chunk_at}
        if not finished:
            r["stopped_at_step"] = self.failed_at if self.failed_at is not None else steps_done
        if self.state is not None:
            t = time.perf_counter()
            r["boundary"] = (self.state.compare_end(self.dir / "state_out")
                             if dumped and finished else None)
            self.seconds["state_compare"] = time.perf_counter() - t
            self.seconds["fast_forward"] = self.seconds_fast_forward
        return r
