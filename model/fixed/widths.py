"""Two's-complement widths and ranges: the bit arithmetic shared by the twin and the RTL.

Every width question of the contract is one of these: the range of a ``bits``-wide signed
or unsigned register, the smallest signed width holding a value or a range, and the
width of an index into ``count`` items.
"""

from __future__ import annotations

__all__ = ["index_bits", "signed_bits", "signed_bits_for", "signed_range", "unsigned_max"]


def signed_range(bits: int) -> tuple[int, int]:
    """``(lo, hi)`` of a ``bits``-wide two's-complement register: ``-2**(b-1), 2**(b-1)-1``."""
    return -(1 << (bits - 1)), (1 << (bits - 1)) - 1


def unsigned_max(bits: int) -> int:
    """Largest value of a ``bits``-wide unsigned register: ``2**bits - 1``."""
    return (1 << bits) - 1


def signed_bits(value: int) -> int:
    """Smallest two's-complement width holding ``value`` (1 for 0 and -1)."""
    v = int(value)
    return (v.bit_length() if v >= 0 else (-v - 1).bit_length()) + 1


def signed_bits_for(lo: int, hi: int, minimum: int = 1) -> int:
    """Smallest two's-complement width holding every integer of ``lo..hi`` (>= ``minimum``)."""
    return max(minimum, signed_bits(lo), signed_bits(hi))


def index_bits(count: int) -> int:
    """Width of an unsigned index into ``count`` items (at least 1)."""
    return max(1, (int(count) - 1).bit_length())
