"""The ``rvsm`` command line: :func:`main` and one module per command family.

Every family module exposes ``register(subparsers)``; :data:`rvsm.sim.cli.main.FAMILIES`
lists them, in the order ``rvsm --help`` shows them. To add a command, write its module
here and add it to that list.
"""

from rvsm.sim.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
