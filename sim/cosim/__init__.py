"""Co-simulation: the generated Verilog on Icarus / Verilator against the fixed twin.

:mod:`.build_cache` builds (cached per contract, through the cocotb adapter
:mod:`.cocotb_adapter`), :mod:`.simulation` runs the cocotb testbench (:mod:`.tb_array`,
:mod:`.tb_stream`) on one stimulus file; :mod:`.verify` is ``rvsm verify``.
"""

#: HDL simulators the runner can build for (``--sim`` of ``rvsm verify`` and the demo).
SIMULATORS: tuple[str, ...] = ("icarus", "verilator")
