"""The cocotb testbenches, one per way of driving an architecture (the parallel array,
the streaming array, its protocol scripts, its long-run harness, the AXI IP), and what
they share (:mod:`.tb_common`)."""
