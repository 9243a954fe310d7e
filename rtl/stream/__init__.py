"""The lane-parallel streaming array: ``P`` pixels per beat, state in banked memories.

:mod:`.signatures` (its streams and threshold bus), :mod:`.dimensions` (sizes and
timing, :class:`~.dimensions.StreamGeometry`), :mod:`.array` (the component,
:class:`~.array.RvsmStreamArray`, composed of one component per pipeline stage, each
with its numpy model: :mod:`.input_stage`, :mod:`.window_stage`, :mod:`.sum_stage`
(retimed orbit sums, :mod:`.pipelined_sum`), :mod:`.position_stage`, :mod:`.state_stage`
(:mod:`.banked_memory`, banks from a :mod:`.memory_target`), :mod:`.output_stage`),
:mod:`.schedule` (the numpy model of its beat schedule and the checker), :mod:`.drive`
(its ``amaranth.sim`` driver), :mod:`.protocol` (cycle-level scripts), the formal
checks (:mod:`.harnesses`, :mod:`.equivalence_harness`, :mod:`.formal_lemmas`),
:mod:`.architecture` (its registry entry).
"""
