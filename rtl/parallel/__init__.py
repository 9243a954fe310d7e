"""The fully parallel array: one adder network and one accumulator per (scale, pixel).

:mod:`.array` (:class:`~.array.RvsmArray`), :mod:`.pixel_cell` (the accumulator cell),
:mod:`.drive` (its ``amaranth.sim`` driver and spike comparison), :mod:`.architecture`
(its registry entry, with the size rule).
"""
