"""Co-simulation builds: how the simulated design is made. cocotb's runner behind an adapter
(``SIMULATORS``), run in a child process; one verified cached build per key; the long-run
harness's Verilog source and sink around the array (:mod:`.chunk_harness`) and the Icarus
netlist rewrite of it (:mod:`.icarus_netlist`); one testbench run on one stimulus file;
Verilator's code coverage of the runs."""
