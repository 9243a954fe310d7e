"""Width arithmetic against brute force and against Amaranth's own shape rules."""

from __future__ import annotations

import pytest
from amaranth.hdl import Shape

from rvsm.model.fixed.widths import (
    index_bits,
    signed_bits,
    signed_bits_for,
    signed_range,
    unsigned_max,
)


@pytest.mark.parametrize("bits", [1, 2, 3, 8, 18, 62])
def test_ranges(bits: int) -> None:
    lo, hi = signed_range(bits)
    assert hi - lo + 1 == 2**bits and lo == -hi - 1
    assert unsigned_max(bits) == 2**bits - 1


def test_signed_bits_is_the_smallest_holding_width() -> None:
    for v in range(-600, 600):
        b = signed_bits(v)
        lo, hi = signed_range(b)
        assert lo <= v <= hi
        if b > 1:
            lo1, hi1 = signed_range(b - 1)
            assert not lo1 <= v <= hi1


@pytest.mark.parametrize(("lo", "hi"), [(0, 0), (-1, 0), (0, 1), (-5, 3), (-128, 127),
                                        (-129, 127), (0, 255), (-3000, 70000)])
def test_signed_bits_for_matches_amaranth(lo: int, hi: int) -> None:
    want = Shape.cast(range(min(lo, -1), max(hi, 0) + 1)).width
    assert signed_bits_for(lo, hi) == want
    assert signed_bits_for(lo, hi, minimum=2) == max(2, want)


def test_index_bits() -> None:
    assert [index_bits(n) for n in (1, 2, 3, 4, 5, 96, 97, 1 << 16)] == [1, 1, 2, 2, 3, 7, 7, 16]
