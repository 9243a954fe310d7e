"""The paper's studies and the demo: Table 1 / Fig. 6 (:mod:`.table`), Fig. 8
(:mod:`.robustness`) and ``rvsm demo`` (:mod:`.demo`)."""
