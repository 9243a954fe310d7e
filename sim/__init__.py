"""Everything that runs the twins: the ``rvsm`` CLI (:mod:`.cli`), RTL co-simulation
(:mod:`.cosim`), the paper's studies and the demo (:mod:`.studies`) and design sweeps
(:mod:`.sweep`)."""
