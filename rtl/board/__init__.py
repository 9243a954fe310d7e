"""The board links: pixels in and spikes out over source-synchronous LVDS pairs.

:mod:`.model` (the protocol in numpy), :mod:`.gearing` (X2 gearing: ECP5 primitives or
the behavioural model), :mod:`.aligner`, :mod:`.deskew`, :mod:`.receiver`,
:mod:`.transmitter`, :mod:`.status` (status signals and registers), :mod:`.front_end`
(receiver -> streaming array -> transmitter), :mod:`.drive` (``amaranth.sim`` drivers).
See ``docs/board.md``.
"""
