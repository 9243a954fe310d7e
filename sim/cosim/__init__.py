"""Co-simulation: the generated Verilog on Icarus / Verilator against the fixed twin.

Split by concern:

- :mod:`.builds`: cocotb's runner behind an adapter (and ``SIMULATORS``), run in a child
  process, one verified cached build per key, the long-run harness's Verilog and its
  Icarus netlist, one testbench run on one stimulus file, and Verilator's code coverage;
- :mod:`.testbenches`: one cocotb testbench per way of driving an architecture;
- :mod:`.long_runs`: long runs in that harness, and the twin's process beside the
  simulator.

Beside them: :mod:`.run_point` (a design point parsed once, its contract built once),
:mod:`.protocol_run` and :mod:`.axis_run` (protocol scripts, the AXI IP), and
:mod:`.verify` (``rvsm verify``). The sub-packages import nothing from this level.
"""
