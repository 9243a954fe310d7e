"""Co-simulation: the generated Verilog on Icarus / Verilator against the fixed twin.

:mod:`.runner` builds (cached per contract) and runs the cocotb testbench
:mod:`.tb_array` on one stimulus file; :mod:`.verify` is ``rvsm verify``.
"""

#: HDL simulators the runner can build for (``--sim`` of ``rvsm verify`` and the demo).
SIMULATORS: tuple[str, ...] = ("icarus", "verilator")
