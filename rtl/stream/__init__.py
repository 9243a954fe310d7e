"""The lane-parallel streaming array: ``P`` pixels per beat, state in banked memories.

:mod:`.signatures` (its streams and threshold bus), :mod:`.geometry` (sizes and
timing, :class:`~.geometry.StreamGeometry`), :mod:`.pipelined_sum` (retimed orbit
sums), :mod:`.banked_memory` (a state memory), :mod:`.array` (the component,
:class:`~.array.RvsmStreamArray`), :mod:`.schedule` (the numpy model of its beat
schedule and the checker), :mod:`.drive` (its ``amaranth.sim`` driver),
:mod:`.architecture` (its registry entry).
"""
