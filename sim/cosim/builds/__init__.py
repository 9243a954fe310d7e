"""Co-simulation builds: cocotb's runner behind an adapter, run in a child process, one
verified cached build per key, and Verilator's code coverage of the runs."""
