"""Long co-simulation runs: the simulation-only source/sink harness around the streaming
array, the twin's process beside the simulator, the Icarus netlist rewrite, and the run."""
