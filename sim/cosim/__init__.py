"""Co-simulation: the generated Verilog on Icarus / Verilator against the fixed twin.

Split by concern: :mod:`.builds` (cocotb's runner, the verified build cache, code
coverage), :mod:`.testbenches` (one cocotb testbench per way of driving an architecture),
:mod:`.long_runs` (the long-run harness and its twin process). Beside them,
:mod:`.run_point` holds a design point parsed once, :mod:`.testbench_run` runs one
testbench on one stimulus file, :mod:`.protocol_run` and
:mod:`.axis_run` the protocol scripts and the AXI IP, and :mod:`.verify` is ``rvsm verify``.
"""

#: HDL simulators the runner can build for (``--sim`` of ``rvsm verify`` and the demo).
SIMULATORS: tuple[str, ...] = ("icarus", "verilator")
