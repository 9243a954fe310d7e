"""The board links' bit-accurate model: pixel codes to per-pair bit streams and back.

Pure numpy; the link RTL (:mod:`rvsm.rtl.board.receiver`,
:mod:`rvsm.rtl.board.transmitter`) is tested against it. Both directions use one
protocol (``docs/board.md``):

* A link is ``pairs = data_pairs + 1`` LVDS pairs plus a forwarded clock. Each pair
  carries one :data:`WORD_BITS`-bit word per core cycle (800 Mbit/s a pair at a 100 MHz
  core: DDR at a 400 MHz edge clock, X2 gearing), bit 0 of a word first on the wire.
* A beat of ``payload_bits`` (pixel codes in, spikes out) is split over the data pairs:
  pair ``j`` carries payload bits ``[8j +: 8]`` (zero padded). The last pair is the
  framing lane: ``SYNC << 4 | parity << 3 | eol << 2 | sof << 1 | valid``, ``parity``
  the XOR of the beat's payload bits. An idle word (no beat) has ``valid = 0`` and every
  data pair sends :data:`TRAIN`.
* Training: every pair sends :data:`TRAIN`, and :data:`MARK` on every
  :data:`TRAIN_PERIOD`-th word on all pairs at once; a receiver aligns each pair's
  words on ``TRAIN`` (bit slip) and lines the pairs up on ``MARK`` (deskew).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GEAR_BITS", "MARK", "SYNC", "TRAIN", "TRAIN_PERIOD", "WORD_BITS", "LinkCapture",
           "LinkFormat", "beat_words", "deserialise", "idle_words", "pixel_beats",
           "serialise", "skewed", "spike_beats_to_frames", "training_words"]

#: Bits a pair carries per word (one word per 100 MHz core cycle).
WORD_BITS = 8
#: Bits a pair carries per system clock (SCLK) of the X2 gearing: half a word.
GEAR_BITS = 4
#: The training word: its 8 rotations differ, so exactly one bit slip matches it.
TRAIN = 0x0F
#: The deskew marker, sent on every pair at once every :data:`TRAIN_PERIOD` words.
MARK = 0x33
#: Training words per period (the last one of each period is :data:`MARK`).
TRAIN_PERIOD = 16
#: High nibble of every framing word in data mode (neither TRAIN's nor MARK's).
SYNC = 0xA
#: Framing word bits.
VALID, SOF, EOL, PARITY = 1, 2, 4, 8


@dataclass(frozen=True)
class LinkFormat:
    """A link carrying beats of ``payload_bits`` bits."""

    payload_bits: int

    @property
    def data_pairs(self) -> int:
        """Pairs carrying payload: ``ceil(payload_bits / 8)``."""
        return -(-self.payload_bits // WORD_BITS)

    @property
    def pairs(self) -> int:
        """Data pairs plus the framing lane (the forwarded clock not counted)."""
        return self.data_pairs + 1

    @property
    def framing_pair(self) -> int:
        """Index of the framing lane (the last pair)."""
        return self.data_pairs


def training_words(fmt: LinkFormat, n: int, start: int = 0) -> np.ndarray:
    """``n`` training words ``(n, pairs) uint8``; word ``k`` (counted from ``start``) is
    :data:`MARK` when ``k % TRAIN_PERIOD == TRAIN_PERIOD - 1``, else :data:`TRAIN`."""
    k = np.arange(start, start + n)
    col = np.where(k % TRAIN_PERIOD == TRAIN_PERIOD - 1, MARK, TRAIN).astype(np.uint8)
    return np.repeat(col[:, None], fmt.pairs, axis=1)


def idle_words(fmt: LinkFormat, n: int) -> np.ndarray:
    """``n`` idle words: data pairs :data:`TRAIN`, framing ``SYNC << 4`` (valid 0)."""
    w = np.full((n, fmt.pairs), TRAIN, dtype=np.uint8)
    w[:, fmt.framing_pair] = SYNC << 4
    return w


def beat_words(fmt: LinkFormat, payload: np.ndarray, sof: np.ndarray, eol: np.ndarray
               ) -> np.ndarray:
    """Beats as link words ``(K, pairs) uint8``: ``payload (K, payload_bits)`` bits
    (bit 0 first), ``sof``/``eol (K,)`` flags."""
    bits = np.asarray(payload, dtype=np.uint8)
    k = bits.shape[0]
    padded = np.zeros((k, fmt.data_pairs * WORD_BITS), dtype=np.uint8)
    padded[:, :fmt.payload_bits] = bits
    words = np.zeros((k, fmt.pairs), dtype=np.uint8)
    words[:, :fmt.data_pairs] = np.packbits(padded, axis=1, bitorder="little")
    parity = (bits.sum(axis=1) & 1).astype(np.uint8)
    words[:, fmt.framing_pair] = (SYNC << 4 | VALID | np.asarray(sof, np.uint8) * SOF
                                  | np.asarray(eol, np.uint8) * EOL | parity * PARITY)
    return words


def pixel_beats(codes: np.ndarray, lanes: int, adc_bits: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Codes ``(T, H, W)`` as the sensor's beats in raster order: payload bits
    ``(T*H*W/P, P*N)`` (lane ``i`` at ``[i*N +: N]``, bit 0 first), ``sof``, ``eol``."""
    c = np.asarray(codes, dtype=np.int64)
    t, h, w = c.shape
    g = w // lanes
    beats = c.reshape(t * h * g, lanes)
    bits = ((beats[:, :, None] >> np.arange(adc_bits)) & 1).astype(np.uint8)
    pos = np.arange(t * h * g) % (h * g)
    return bits.reshape(len(beats), lanes * adc_bits), pos == 0, pos % g == g - 1


def serialise(words: np.ndarray) -> np.ndarray:
    """Words ``(K, pairs)`` as bit streams ``(pairs, K*8) uint8``, bit 0 of a word first."""
    w = np.asarray(words, dtype=np.uint8)
    return np.unpackbits(w.T[:, :, None], axis=2, bitorder="little").reshape(w.shape[1], -1)


def skewed(bits: np.ndarray, delays: np.ndarray, fill: int = 0) -> np.ndarray:
    """Bit streams ``(pairs, B)`` with pair ``i`` delayed by ``delays[i]`` bits (``fill``
    bits in front; every stream keeps its length ``B``)."""
    out = np.full_like(bits, fill)
    for i, d in enumerate(np.asarray(delays, dtype=np.int64)):
        out[i, d:] = bits[i, :bits.shape[1] - d]
    return out


@dataclass(frozen=True)
class LinkCapture:
    """What :func:`deserialise` read: the beats' payload bits ``(K, payload_bits)``,
    ``sof``/``eol (K,)``, per pair the bit offset of its aligned words (``slips``) and
    the words that broke the protocol (``errors``: parity errors count on the framing
    lane)."""

    payload: np.ndarray
    sof: np.ndarray
    eol: np.ndarray
    slips: np.ndarray
    errors: np.ndarray


def _lane_start(stream: np.ndarray) -> int:
    """Bit offset of the first :data:`MARK` preceded by four aligned :data:`TRAIN`."""
    n = (len(stream) - 7)
    packed = np.array([int(np.packbits(stream[b:b + 8], bitorder="little")[0])
                       for b in range(n)])
    for b in range(4 * WORD_BITS, n):
        if packed[b] == MARK and all(packed[b - WORD_BITS * j] == TRAIN for j in range(1, 5)):
            return b
    raise ValueError("no training sequence (4 TRAIN words then MARK) on a pair")


def deserialise(fmt: LinkFormat, bits: np.ndarray) -> LinkCapture:
    """Read bit streams ``(pairs, B)``: align each pair on its first MARK after training
    (so skew and bit slip vanish), then read the words in order: training and idle words
    are checked, data beats kept. Raises ``ValueError`` when a pair never trains."""
    starts = np.array([_lane_start(s) for s in np.asarray(bits, dtype=np.uint8)])
    n = min((bits.shape[1] - s) // WORD_BITS for s in starts)
    words = np.stack([np.packbits(bits[i, s:s + n * WORD_BITS].reshape(n, WORD_BITS),
                                  axis=1, bitorder="little")[:, 0]
                      for i, s in enumerate(starts)], axis=1)
    errors = np.zeros(fmt.pairs, dtype=np.int64)
    keep, sof, eol = [], [], []
    f = fmt.framing_pair
    for row in words:
        frame = int(row[f])
        data = row[:fmt.data_pairs]
        if frame in (TRAIN, MARK):
            errors[:f] += data != frame
        elif frame >> 4 != SYNC:
            errors[f] += 1
        elif frame & VALID:
            payload = np.unpackbits(data, bitorder="little")[:fmt.payload_bits]
            errors[f] += int(payload.sum() & 1) != bool(frame & PARITY)
            keep.append(payload)
            sof.append(bool(frame & SOF))
            eol.append(bool(frame & EOL))
        else:
            errors[:f] += data != TRAIN
    payload = np.array(keep, dtype=np.uint8).reshape(len(keep), fmt.payload_bits)
    return LinkCapture(payload, np.array(sof, bool), np.array(eol, bool), starts % WORD_BITS,
                       errors)


def spike_beats_to_frames(capture: LinkCapture, num_scales: int, height: int, width: int,
                          lanes: int) -> np.ndarray:
    """Spike beats (payload ``pos`` then ``neg``, ``S*P`` bits each, bit ``s*P + i``) as
    spikes ``(T, S, H, W) int8`` of the whole frames received; positions come from the
    framing alone (a frame starts at ``sof``; ``eol`` must close every row)."""
    n = num_scales * lanes
    g = width // lanes
    per_frame = height * g
    starts = np.flatnonzero(capture.sof)
    if len(starts) == 0:
        return np.zeros((0, num_scales, height, width), dtype=np.int8)
    beats = capture.payload[starts[0]:]
    frames = len(beats) // per_frame
    beats = beats[:frames * per_frame]
    eol = capture.eol[starts[0]:starts[0] + len(beats)]
    if not np.array_equal(eol, np.arange(len(beats)) % g == g - 1):
        raise ValueError("end-of-line flags disagree with the frame's geometry")
    spikes = beats[:, :n].astype(np.int8) - beats[:, n:2 * n].astype(np.int8)
    return spikes.reshape(frames, height, g, num_scales, lanes) \
        .transpose(0, 3, 1, 2, 4).reshape(frames, num_scales, height, width)
