"""Mutation testing of the verification itself (``rvsm mutate``): :mod:`.checks` (the
co-simulation scenarios a mutant must fail), :mod:`.run` (every mutant against them and
the formal checks, and the report)."""
