"""Formal verification with pip-only tools: sby runs of Amaranth harnesses (``yowasp-sby``
with ``smtbmc yices`` or ``z3``): :mod:`.sby` (one sby run), :mod:`.runner` (the checks of
one architecture at one point, ``rvsm formal``), :mod:`.plan` and :mod:`.plan_run` (a
matrix of such runs, ``rvsm formal --plan``)."""
