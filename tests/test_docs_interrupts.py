"""``docs/interrupts.md``: every command has a row, and every row names a test that exists."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from rvsm.sim.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "interrupts.md"
TEST = re.compile(r"`(tests/[\w/]+\.py)::(test_\w+)`")


def _rows() -> dict[str, str]:
    """Command -> its row's text, from the table of ``docs/interrupts.md``."""
    rows = {}
    for line in DOC.read_text().splitlines():
        found = re.match(r"\|\s*`(\w+)`\s*\|", line)
        if found:
            rows[found.group(1)] = line
    return rows


def _tests_in(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    return {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}


def test_every_command_has_a_row() -> None:
    assert sorted(_rows()) == sorted(c.name for c in COMMANDS)


def test_every_row_names_an_existing_test() -> None:
    for command, row in _rows().items():
        named = TEST.findall(row)
        assert named, f"the row of {command} names no test"
        for path, name in named:
            assert (ROOT / path).is_file(), f"{command}: {path} does not exist"
            assert name in _tests_in(ROOT / path), f"{command}: {path}::{name} does not exist"
