"""Every source path and Python name quoted in the README and ``docs/*.md`` exists.

A restructuring moves modules; the docs must follow. Two kinds of reference are checked:
a repository path ending in ``.py`` under ``model/``, ``rtl/``, ``sim/``, ``tests/`` or
``scripts/`` must be a file, and a dotted name ``rvsm.model...`` / ``rvsm.rtl...`` /
``rvsm.sim...`` must import (its longest importable module prefix, then attributes).
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]
PATH = re.compile(r"\b((?:model|rtl|sim|tests|scripts)/[\w/]+\.py)\b")
NAME = re.compile(r"\brvsm\.(?:model|rtl|sim)(?:\.\w+)+")


def resolves(name: str) -> bool:
    """True when ``name`` is an importable module, or one followed by attributes."""
    parts = name.split(".")
    for i in range(len(parts), 1, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def stale_references(doc: Path) -> list[str]:
    """``line: reference`` of every path or name in ``doc`` that does not exist."""
    bad = []
    for n, line in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1):
        bad += [f"{n}: {p}" for p in PATH.findall(line) if not (ROOT / p).is_file()]
        bad += [f"{n}: {m}" for m in NAME.findall(line) if not resolves(m)]
    return bad


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_quoted_paths_and_names_exist(doc: Path) -> None:
    bad = stale_references(doc)
    assert not bad, f"{doc.relative_to(ROOT)} quotes what does not exist:\n" + "\n".join(bad)


def test_a_stale_reference_is_found(tmp_path: Path) -> None:
    doc = tmp_path / "x.md"
    doc.write_text("see `model/fixed/contract.py` and `rvsm.model.fixed.contract.ArrayContract`\n"
                   "gone: `model/samplers.py`, `rvsm.model.fixed.contract.NoSuchThing`,"
                   " `rvsm.model.nosuchmodule`\n")
    assert stale_references(doc) == ["2: model/samplers.py",
                                     "2: rvsm.model.fixed.contract.NoSuchThing",
                                     "2: rvsm.model.nosuchmodule"]
