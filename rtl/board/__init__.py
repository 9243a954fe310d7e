"""The board links: pixels in and spikes out over source-synchronous LVDS pairs.

:mod:`.model` (the protocol in numpy), :mod:`.gearing` (X2 gearing: ECP5 primitives or
the behavioural model), :mod:`.aligner`, :mod:`.deskew`, :mod:`.receiver`,
:mod:`.transmitter`, :mod:`.status` (status signals and registers), :mod:`.front_end`
(receiver -> streaming array -> transmitter), :mod:`.ip_front_end` (receiver -> AXI IP
-> transmitter, registers over SPI), :mod:`.spi_bridge` and :mod:`.spi_model` (the SPI
register bus and its model), :mod:`.drive` and :mod:`.spi_drive` (``amaranth.sim``
drivers).
See ``docs/board.md``.
"""
