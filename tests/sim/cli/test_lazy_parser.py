"""``rvsm --help`` and ``rvsm --version`` import no heavy module (issue 33 deliverable 5), and
the lazily built parser says exactly what the full one says."""

from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from rvsm.sim.cli.commands import COMMANDS, FAMILY_NAMES
from rvsm.sim.cli.main import build_parser, family_module

#: Modules that take most of a second to import; none belongs in ``rvsm --help``.
HEAVY = ("numba", "matplotlib", "amaranth", "scipy", "numpy")


def _imported(*argv: str) -> set[str]:
    """Top-level packages a fresh ``rvsm ARGV`` imports (from ``python -X importtime``)."""
    run = subprocess.run([sys.executable, "-X", "importtime", "-m", "rvsm.sim.console", *argv],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "usage: rvsm" in run.stdout or argv == ("--version",)
    lines = [ln.split("|")[-1].strip() for ln in run.stderr.splitlines()
             if ln.startswith("import time:")]
    return {name.split(".")[0] for name in lines}


@pytest.mark.parametrize("argv", [("--help",), ("--version",)])
def test_help_and_version_import_nothing_heavy(argv: tuple[str, ...]) -> None:
    imported = _imported(*argv)
    assert "rvsm" in imported  # the parse saw the imports at all
    assert not imported & set(HEAVY), sorted(imported & set(HEAVY))


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


@pytest.mark.parametrize("family", FAMILY_NAMES)
def test_each_family_registers_its_listed_commands(family: str) -> None:
    sub = argparse.ArgumentParser().add_subparsers()
    family_module(family).register(sub)
    listed = [(c.name, c.summary) for c in COMMANDS if c.family == family]
    assert [(a.dest, a.help) for a in sub._choices_actions] == listed


def test_overview_is_the_full_parsers_help() -> None:
    assert build_parser(()).format_help() == build_parser().format_help()


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c.name)
def test_a_commands_help_is_the_full_parsers(command) -> None:
    lazy = _subparsers(build_parser((command.family,))).choices[command.name]
    full = _subparsers(build_parser()).choices[command.name]
    assert lazy.format_help() == full.format_help()
