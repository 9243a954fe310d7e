"""The picture of the packages in ``docs/architecture.md`` is the real one.

The picture is a Mermaid graph of every package (folder) of ``model/``, ``rtl/`` and
``sim/`` and the imports between them, function-local ones included (the arrows of
:mod:`tests.test_layering`), drawn as the transitive reduction: an arrow A --> B is shown
unless A reaches B through other arrows anyway, so every dependency is in the picture once.
The test fails when the picture and the code differ; ``python tests/test_architecture_map.py``
prints the picture to paste.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_layering import PACKAGES, ROOT, all_arrows, folder_arrows, module_files  # noqa: E402

DOC = ROOT / "docs" / "architecture.md"
_BLOCK = re.compile(r"```mermaid\n(graph .*?)```", re.S)


def package_graph() -> dict[str, set[str]]:
    """Folder -> the folders it imports (acyclic: tests/test_layering.py checks that)."""
    modules = module_files(PACKAGES)
    graph: dict[str, set[str]] = {m: set() for m, p in modules.items()
                                  if p.name == "__init__.py"}
    for a in folder_arrows(all_arrows(PACKAGES), modules):
        graph.setdefault(a.source, set()).add(a.target)
    return graph


def reduction(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The transitive reduction of an acyclic ``graph``."""
    def reach(node: str, seen: set[str]) -> set[str]:
        for nxt in graph.get(node, ()):
            if nxt not in seen:
                seen.add(nxt)
                reach(nxt, seen)
        return seen

    out = {}
    for node, targets in graph.items():
        indirect = set()
        for t in targets:
            indirect |= reach(t, set())
        out[node] = targets - indirect
    return out


def _name(package: str) -> str:
    return package.removeprefix("rvsm.").replace(".", "/") + "/"


def _id(package: str) -> str:
    return package.removeprefix("rvsm.").replace(".", "_")


def mermaid() -> str:
    """The picture: one subgraph per layer, the reduced arrows, sorted (stable text)."""
    graph = reduction(package_graph())
    lines = ["graph BT"]
    for top in ("rvsm.model", "rvsm.rtl", "rvsm.sim"):
        lines.append(f"  subgraph {_id(top)}_layer [{top.removeprefix('rvsm.')}]")
        for p in sorted(n for n in graph if n == top or n.startswith(top + ".")):
            lines.append(f'    {_id(p)}["{_name(p)}"]')
        lines.append("  end")
    for source in sorted(graph):
        for target in sorted(graph[source]):
            lines.append(f"  {_id(source)} --> {_id(target)}")
    return "\n".join(lines) + "\n"


def test_the_package_picture_in_the_docs_is_the_code() -> None:
    found = _BLOCK.search(DOC.read_text())
    assert found, "docs/architecture.md has no ```mermaid graph block"
    assert found.group(1) == mermaid(), (
        "docs/architecture.md's package picture differs from the imports: paste the output "
        "of `python tests/test_architecture_map.py`")


def test_reduction_keeps_reachability() -> None:
    graph = {"a": {"b", "c"}, "b": {"c"}, "c": set(), "d": {"a", "c"}}
    assert reduction(graph) == {"a": {"b"}, "b": {"c"}, "c": set(), "d": {"a"}}


if __name__ == "__main__":
    print(mermaid(), end="")
