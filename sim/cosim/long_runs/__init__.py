"""Long co-simulation runs in the harness of :mod:`rvsm.sim.cosim.builds.chunk_harness`:
the twin's process beside the simulator (:mod:`.chunk_twin`), the cocotb testbench that
hands it the chunk files (:mod:`.tb_stream_chunks`), and the run chunk by chunk with a
waveform window around the first mismatch (:mod:`.long_run`)."""
