"""The layering rule ``model <- rtl <- sim``, checked on every module's imports.

Every module of ``rvsm.model``, ``rvsm.rtl`` and ``rvsm.sim`` (the folders ``model/``,
``rtl/``, ``sim/``) is parsed with :mod:`ast`, and every ``import`` / ``from ... import``
statement naming an ``rvsm.*`` module counts as an arrow, wherever it stands: at the top,
inside a function, under ``if TYPE_CHECKING:``. Relative imports are resolved to full names
(``from .x import y``, ``from . import x``), and ``from pkg import name`` is an arrow to the
module ``pkg.name`` when that is a module, else to ``pkg``. A string naming a module (a
cocotb testbench module passed by name, ``importlib.import_module``) is not an import.

The tests fail on

- an arrow against the layers: ``rvsm.model`` imports nothing of ``rvsm.rtl`` or
  ``rvsm.sim``, ``rvsm.rtl`` nothing of ``rvsm.sim`` (message: ``file:line: a -> b``);
- an import circle between modules (message: the cycle, each arrow with its file:line);
- an import loop between folders (packages): the same arrows, each from the folder of
  its source file to the folder of its target (a package's ``__init__.py`` is in its
  own folder; a sub-package is a folder of its own, so a parent folder importing a
  sub-package that imports the parent folder back is a loop), with the file:line of
  each arrow. :data:`KNOWN_FOLDER_LOOPS` lists the loops other work of issue 31 removes;
  any other loop fails, and so does a listed one that is gone.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The layers, lowest first: a module may import its own layer and the ones before it.
LAYERS = ("rvsm.model", "rvsm.rtl", "rvsm.sim")
#: Package name -> its folder (``package-dir`` in ``pyproject.toml``).
PACKAGES = {"rvsm.model": ROOT / "model", "rvsm.rtl": ROOT / "rtl", "rvsm.sim": ROOT / "sim"}

@dataclass(frozen=True)
class Arrow:
    """One import: ``source`` imports ``target`` at ``path:line``."""

    source: str
    target: str
    path: Path
    line: int

    def __str__(self) -> str:
        try:
            where = self.path.relative_to(ROOT)
        except ValueError:
            where = self.path
        return f"{where}:{self.line}: {self.source} -> {self.target}"


def module_files(packages: dict[str, Path]) -> dict[str, Path]:
    """Module name -> source file, for every ``*.py`` under each package folder."""
    modules = {}
    for package, folder in packages.items():
        for path in sorted(folder.rglob("*.py")):
            parts = path.relative_to(folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join((package, *parts))] = path
    return modules


def _known(name: str, modules: dict[str, Path]) -> str | None:
    """The longest prefix of the dotted ``name`` that is a module, or None."""
    parts = name.split(".")
    for n in range(len(parts), 0, -1):
        prefix = ".".join(parts[:n])
        if prefix in modules:
            return prefix
    return None


def imports_of(module: str, path: Path, modules: dict[str, Path]) -> list[Arrow]:
    """Every arrow from ``module`` (source file ``path``) to a module in ``modules``."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    arrows = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = package.split(".")
                anchor = anchor[:len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            names = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base
                     for alias in node.names]
        for name in names:
            target = _known(name, modules) if name.startswith("rvsm.") else None
            if target is not None and target != module:
                arrows.append(Arrow(module, target, path, node.lineno))
    return sorted(set(arrows), key=lambda a: (a.line, a.target))


def all_arrows(packages: dict[str, Path]) -> list[Arrow]:
    """The arrows of every module of ``packages``."""
    modules = module_files(packages)
    return [a for module, path in modules.items() for a in imports_of(module, path, modules)]


def layer(module: str) -> int:
    """The index in :data:`LAYERS` of the layer holding ``module``."""
    return next(i for i, top in enumerate(LAYERS)
                if module == top or module.startswith(top + "."))


def wrong_way(arrows: list[Arrow]) -> list[Arrow]:
    """The arrows from a lower layer to a higher one (``model -> rtl``, ``rtl -> sim``...)."""
    return [a for a in arrows if layer(a.source) < layer(a.target)]


def circles(arrows: list[Arrow]) -> list[list[Arrow]]:
    """One closed path of arrows through each import circle (each strongly connected set
    of two or more modules), found with Tarjan's algorithm."""
    graph: dict[str, dict[str, Arrow]] = {}
    for a in arrows:
        graph.setdefault(a.source, {}).setdefault(a.target, a)
        graph.setdefault(a.target, {})
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[set[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                components.append(component)

    for v in sorted(graph):
        if v not in index:
            connect(v)
    return [_closed_path(graph, c) for c in components]


def _closed_path(graph: dict[str, dict[str, Arrow]], component: set[str]) -> list[Arrow]:
    """A shortest closed path of arrows inside ``component``, from its first module."""
    start = min(component)
    came: dict[str, Arrow] = {}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w, arrow in sorted(graph[v].items()):
                if w not in component:
                    continue
                if w == start:
                    path = [arrow]
                    while path[0].source != start:
                        path.insert(0, came[path[0].source])
                    return path
                if w not in came:
                    came[w] = arrow
                    nxt.append(w)
        frontier = nxt
    raise AssertionError(f"no closed path in the component {sorted(component)}")


def folder_of(module: str, modules: dict[str, Path]) -> str:
    """The package whose folder holds ``module``'s file (a package is its own)."""
    return module if modules[module].name == "__init__.py" else module.rpartition(".")[0]


def folder_arrows(arrows: list[Arrow], modules: dict[str, Path]) -> list[Arrow]:
    """Each arrow between two different folders, as an arrow between the folders (with
    the file:line of the import that makes it)."""
    out = []
    for a in arrows:
        source, target = folder_of(a.source, modules), folder_of(a.target, modules)
        if source != target:
            out.append(Arrow(source, target, a.path, a.line))
    return out


def folder_loops(packages: dict[str, Path]) -> list[list[Arrow]]:
    """One closed path of folder arrows through each loop of folders."""
    modules = module_files(packages)
    return circles(folder_arrows(all_arrows(packages), modules))


def describe(cycle: list[Arrow]) -> str:
    """``a -> b -> a`` followed by each arrow's file:line."""
    head = " -> ".join([a.source for a in cycle] + [cycle[0].source])
    return head + "".join(f"\n    {a}" for a in cycle)


# --- the tree --------------------------------------------------------------------------

def test_every_module_is_walked():
    modules = module_files(PACKAGES)
    assert {"rvsm.model", "rvsm.rtl", "rvsm.sim", "rvsm.sim.cli.main",
            "rvsm.model.fixed.contract"} <= set(modules)
    arrows = all_arrows(PACKAGES)
    assert len(modules) > 90 and len(arrows) > 200
    assert {layer(a.source) for a in arrows} == {0, 1, 2}


def test_no_import_against_the_layers():
    bad = wrong_way(all_arrows(PACKAGES))
    assert not bad, "imports against model <- rtl <- sim:\n" + "\n".join(map(str, bad))


def test_no_import_circles():
    found = circles(all_arrows(PACKAGES))
    assert not found, "import circles:\n" + "\n".join(describe(c) for c in found)


#: Folder loops that other deliverables of issue 31 remove, each as the set of folders of
#: its strongly connected component: the RTL registry (``rtl/architectures/registry.py``) and the
#: architectures' packages importing each other, with ``rtl/stream`` importing
#: ``rtl/fpga`` (the ECP5 memory); ``sim/cosim`` and its sub-packages. Delete a line when
#: its loop is gone (the test says so).
KNOWN_FOLDER_LOOPS: set[frozenset[str]] = set()


def _component(cycle: list[Arrow], arrows: list[Arrow]) -> frozenset[str]:
    """The folders of the strongly connected component through ``cycle``."""
    graph: dict[str, set[str]] = {}
    for a in arrows:
        graph.setdefault(a.source, set()).add(a.target)

    def reach(start: str, edges: dict[str, set[str]]) -> set[str]:
        seen, todo = {start}, [start]
        while todo:
            for w in edges.get(todo.pop(), ()):
                if w not in seen:
                    seen.add(w)
                    todo.append(w)
        return seen

    back: dict[str, set[str]] = {}
    for v, ws in graph.items():
        for w in ws:
            back.setdefault(w, set()).add(v)
    start = cycle[0].source
    return frozenset(reach(start, graph) & reach(start, back))


def test_no_folder_loops():
    """No loop between folders, function-local imports counted (the model's sensor
    packages once formed one: decode, events, fixed, sampling, spikes)."""
    modules = module_files(PACKAGES)
    arrows = folder_arrows(all_arrows(PACKAGES), modules)
    found = {_component(c, arrows): c for c in circles(arrows)}
    new = [f"folders {', '.join(sorted(comp))}, e.g. {describe(c)}"
           for comp, c in found.items() if comp not in KNOWN_FOLDER_LOOPS]
    assert not new, "import loops between folders:\n" + "\n".join(new)
    gone = KNOWN_FOLDER_LOOPS - set(found)
    assert not gone, f"known folder loops no longer found, delete them: {sorted(map(sorted, gone))}"
    assert not any(comp & {f"rvsm.model.{p}" for p in
                           ("decode", "events", "fixed", "sampling", "spikes")}
                   for comp in found)


# --- the checker, on a synthetic tree --------------------------------------------------

def _tree(tmp_path: Path, files: dict[str, str]) -> dict[str, Path]:
    for name, text in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return {top: tmp_path / top.split(".")[1] for top in LAYERS}


def test_checker_finds_a_wrong_way_arrow_and_a_circle(tmp_path):
    packages = _tree(tmp_path, {
        "model/__init__.py": "",
        "model/a.py": "def f():\n    from rvsm.rtl import b\n    return b\n",
        "model/c.py": "from typing import TYPE_CHECKING\n"
                      "if TYPE_CHECKING:\n    from .d import D\n",
        "model/d.py": "from . import c\n",
        "rtl/__init__.py": "",
        "rtl/b.py": "import rvsm.model.a\nTB = 'rvsm.sim.tb'\n",
        "sim/__init__.py": "",
        "sim/tb.py": "from ..model import a\nfrom rvsm.rtl.b import TB\n",
    })
    arrows = all_arrows(packages)
    assert [str(a).split(": ", 1)[1] for a in wrong_way(arrows)] == [
        "rvsm.model.a -> rvsm.rtl.b"]
    assert str(wrong_way(arrows)[0]) == f"{tmp_path / 'model' / 'a.py'}:2: " \
        "rvsm.model.a -> rvsm.rtl.b"
    found = circles(arrows)
    assert sorted(sorted(a.source for a in c) for c in found) == [
        ["rvsm.model.a", "rvsm.rtl.b"], ["rvsm.model.c", "rvsm.model.d"]]
    text = "\n".join(describe(c) for c in found)
    assert "rvsm.model.c -> rvsm.model.d -> rvsm.model.c" in text
    assert "model/c.py:3: rvsm.model.c -> rvsm.model.d" in text
    # the string naming rvsm.sim.tb is not an import; sim's relative import is resolved
    assert {(a.source, a.target) for a in arrows} == {
        ("rvsm.model.a", "rvsm.rtl.b"), ("rvsm.model.c", "rvsm.model.d"),
        ("rvsm.model.d", "rvsm.model.c"), ("rvsm.rtl.b", "rvsm.model.a"),
        ("rvsm.sim.tb", "rvsm.model.a"), ("rvsm.sim.tb", "rvsm.rtl.b")}


def test_checker_passes_a_clean_tree(tmp_path):
    packages = _tree(tmp_path, {
        "model/__init__.py": "from .a import f\n",
        "model/a.py": "import numpy\n\ndef f():\n    return numpy.zeros(1)\n",
        "rtl/__init__.py": "",
        "rtl/b.py": "from rvsm.model import a\nfrom rvsm.model.a import f\n",
        "sim/__init__.py": "",
        "sim/c.py": "from rvsm.rtl import b\nimport rvsm.model\n",
    })
    arrows = all_arrows(packages)
    assert not wrong_way(arrows) and not circles(arrows)
    assert ("rvsm.model", "rvsm.model.a") in {(a.source, a.target) for a in arrows}


def test_checker_finds_a_folder_loop_that_no_module_circle_shows(tmp_path):
    """Two folders importing each other through different modules, one import inside a
    function: no module circle, one folder loop."""
    packages = _tree(tmp_path, {
        "model/__init__.py": "",
        "model/low/__init__.py": "",
        "model/low/files.py": "def open_any():\n    from rvsm.model.high.lists import L\n"
                              "    return L\n",
        "model/low/arrays.py": "A = 1\n",
        "model/high/__init__.py": "",
        "model/high/lists.py": "from rvsm.model.low.arrays import A\nL = A\n",
        "model/top.py": "from rvsm.model.low import files\n",
        "rtl/__init__.py": "",
        "sim/__init__.py": "",
    })
    arrows = all_arrows(packages)
    assert not circles(arrows) and not wrong_way(arrows)
    found = folder_loops(packages)
    assert len(found) == 1
    text = describe(found[0])
    assert "rvsm.model.high -> rvsm.model.low -> rvsm.model.high" in text
    assert "model/low/files.py:2: rvsm.model.low -> rvsm.model.high" in text
    assert "model/high/lists.py:1: rvsm.model.high -> rvsm.model.low" in text
    # the root folder importing a sub-package is no loop while nothing imports it back
    assert {(a.source, a.target) for a in folder_arrows(arrows, module_files(packages))} \
        == {("rvsm.model.low", "rvsm.model.high"), ("rvsm.model.high", "rvsm.model.low"),
            ("rvsm.model", "rvsm.model.low")}


def test_checker_finds_a_parent_and_sub_package_loop(tmp_path):
    """A module of a parent folder importing a sub-package that imports the parent
    folder back is a folder loop (a registry beside the values it registers)."""
    packages = _tree(tmp_path, {
        "model/__init__.py": "",
        "rtl/__init__.py": "",
        "rtl/registry.py": "from rvsm.rtl.arch.value import V\n",
        "rtl/capabilities.py": "class Cap: ...\n",
        "rtl/arch/__init__.py": "",
        "rtl/arch/value.py": "from rvsm.rtl.capabilities import Cap\nV = Cap()\n",
        "sim/__init__.py": "",
    })
    assert not circles(all_arrows(packages))
    found = folder_loops(packages)
    assert [sorted({a.source for a in c}) for c in found] == [["rvsm.rtl", "rvsm.rtl.arch"]]


def test_every_package_is_listed_in_pyproject():
    """A sub-package missing from ``[tool.setuptools] packages`` would be left out of a
    wheel (an editable install hides it)."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {name for name, path in module_files(PACKAGES).items()
             if path.name == "__init__.py"}
    assert found == listed, f"missing: {sorted(found - listed)}; stale: {sorted(listed - found)}"
