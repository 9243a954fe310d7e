"""The ``rvsm`` command line: :func:`main` and one module per command family.

Every family module exposes ``register(subparsers)``; :data:`rvsm.sim.cli.commands.COMMANDS`
lists every command with its family and help line, in the order ``rvsm --help`` shows them.
To add a command, register it in its family's module and add it to that table.
"""

from rvsm.sim.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
