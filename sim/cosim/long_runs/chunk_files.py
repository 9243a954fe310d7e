"""The long-run harness's chunk files (:mod:`rvsm.sim.cosim.builds.chunk_harness`):
hexadecimal ``$readmemh`` / ``$writememh`` text, one word per line, most significant
digit first: input beats and threshold writes written for the harness
(:func:`encode_input_beats`, :func:`encode_threshold_writes`), its output beats read
back (:func:`decode_output_beats`)."""

from __future__ import annotations

import numpy as np

from rvsm.model.infra.errors import ToolError

__all__ = ["decode_output_beats", "encode_input_beats", "encode_threshold_writes"]

_HEX = np.frombuffer(b"0123456789abcdef", dtype=np.uint8)
_NIBBLE = np.full(256, 255, dtype=np.uint8)
for _i, _c in enumerate(b"0123456789abcdef"):
    _NIBBLE[_c] = _i
for _i, _c in enumerate(b"ABCDEF"):
    _NIBBLE[_c] = 10 + _i


def encode_input_beats(beats: np.ndarray, bits: int, total_bits: int) -> bytes:
    """Input beats ``(K, P)`` codes of ``bits`` each as ``$readmemh`` text: one line per
    beat, lane ``i`` at bits ``[i*bits +: bits]``, ``ceil(total_bits / 4)`` hex digits."""
    v = np.asarray(beats, dtype=np.uint32)
    k, p = v.shape
    digits = -(-total_bits // 4)
    lane_bits = ((v[:, :, None] >> np.arange(bits, dtype=np.uint32)) & 1).astype(np.uint8)
    flat = np.zeros((k, digits * 4), dtype=np.uint8)  # little-endian bit columns
    flat[:, : p * bits] = lane_bits.reshape(k, p * bits)
    nib = flat.reshape(k, digits, 4) @ np.array([1, 2, 4, 8], dtype=np.uint8)
    text = np.empty((k, digits + 1), dtype=np.uint8)
    text[:, :digits] = _HEX[nib[:, ::-1]]
    text[:, digits] = ord("\n")
    return text.tobytes()


def encode_threshold_writes(writes: list[tuple[int, int]], addr_bits: int,
                            data_bits: int) -> bytes:
    """Threshold writes ``[(addr, data), ...]`` as the harness's ``$readmemh`` text: one
    ``{addr, data}`` word per line (``addr`` above ``data_bits`` bits of data)."""
    digits = -(-(addr_bits + data_bits) // 4)
    return "".join(f"{(a << data_bits) | d:0{digits}x}\n" for a, d in writes).encode()


def decode_output_beats(text: bytes, bits: int) -> tuple[np.ndarray, np.ndarray]:
    """``$writememh`` text of ``bits``-bit words: ``(K, bits) uint8`` little-endian bit
    columns and ``(K,) bool``, True where a line held X/Z (its bits read as 0).

    Comment lines (``//``) and blank lines are skipped."""
    digits = -(-bits // 4)
    while text.startswith(b"//"):  # Icarus heads the file with "// 0x00000000"
        text = text[text.find(b"\n") + 1:] if b"\n" in text else b""
    fast = np.frombuffer(text, dtype=np.uint8)
    if fast.size and fast.size % (digits + 1) == 0:  # only fixed-width lines: no split
        rows = fast.reshape(-1, digits + 1)
        if (rows[:, digits] == ord("\n")).all() and not (rows[:, 0] == ord("/")).any():
            return _decode_digits(rows[:, :digits], bits)
    lines = [ln.strip() for ln in text.split(b"\n")]
    lines = [ln for ln in lines if ln and not ln.startswith(b"//")]
    if not lines:
        return np.zeros((0, bits), dtype=np.uint8), np.zeros(0, dtype=bool)
    if any(len(ln) != digits for ln in lines):
        bad = next(ln for ln in lines if len(ln) != digits)
        raise ToolError(f"harness output line has {len(bad)} hex digits, expected {digits}")
    raw = np.frombuffer(b"".join(lines), dtype=np.uint8).reshape(len(lines), digits)
    return _decode_digits(raw, bits)


def _decode_digits(raw: np.ndarray, bits: int) -> tuple[np.ndarray, np.ndarray]:
    """Hex digit characters ``(K, digits) uint8`` (most significant first) as
    :func:`decode_output_beats` returns them."""
    nib = _NIBBLE[raw]
    unknown = (nib == 255).any(axis=1)
    nib = np.where(nib == 255, 0, nib)[:, ::-1]  # least significant digit first
    bits_le = ((nib[:, :, None] >> np.arange(4, dtype=np.uint8)) & 1).reshape(len(raw), -1)
    return bits_le[:, :bits].astype(np.uint8), unknown
