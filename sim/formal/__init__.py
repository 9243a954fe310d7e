"""Formal verification with pip-only tools: sby runs of Amaranth harnesses (``yowasp-sby``
with ``smtbmc z3``)."""
