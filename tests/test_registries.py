"""The architecture registry is the one place that knows architectures by name.

Every module of ``rvsm.sim`` (``sim/``) and every module of ``rvsm.rtl`` outside the
architecture packages and the registry is parsed with :mod:`ast`; the test fails on

- an import of an architecture package (``rvsm.rtl.stream``, ``rvsm.rtl.parallel``,
  ``rvsm.rtl.ip``) from ``sim/``, wherever it stands (at the top, inside a function,
  ``from rvsm.rtl import stream``), or a module name given to ``importlib`` as text. The
  one exception: a wrapper's own cocotb testbench (the module a registered wrapper names
  as its ``testbench``, e.g. the AXI IP's) may import the wrapper's package, its
  interface (register map, AXI drivers, cycle model), not an array's internals;
- a branch on a registered architecture's or wrapper's name (``"stream"``,
  ``"parallel"``, ``"stream_axis"``): a comparison with it (``arch == "stream"``,
  ``name in ("stream",)``), a table keyed by names (``{"stream": ...}``), a ``case``.
  What differs between architectures is a capability of the
  :class:`~rvsm.rtl.capabilities.Architecture` value the registry hands out. Choosing
  one architecture by its name (``get_architecture("stream")``, ``arch="stream"``) is
  not a branch.

The checker is tested on a synthetic source too, so the test can fail.
"""

from __future__ import annotations

import ast
from pathlib import Path

from rvsm.rtl.architectures.registry import ARCHITECTURES, WRAPPERS

ROOT = Path(__file__).resolve().parents[1]
#: The packages that define architectures (the registry imports them; nothing in sim may).
ARCHITECTURE_PACKAGES = ("rvsm.rtl.stream", "rvsm.rtl.parallel", "rvsm.rtl.ip")
#: Every name the registry answers to.
NAMES = {*ARCHITECTURES, *(w.name for w in WRAPPERS.values())}


def _module(path: Path, package: str, folder: Path) -> str:
    parts = path.relative_to(folder).with_suffix("").parts
    parts = parts[:-1] if parts[-1] == "__init__" else parts
    return ".".join((package, *parts))


def _imported(node: ast.AST) -> list[str]:
    """Module names an import statement, or an ``importlib.import_module("...")`` /
    ``__import__("...")`` call, names (absolute ones: sim never imports rtl relatively)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if isinstance(node, ast.ImportFrom) and not node.level and node.module:
        if _package(node.module) is not None:
            return [node.module]
        return [f"{node.module}.{a.name}" for a in node.names]  # from rvsm.rtl import ip
    if isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
        if name in ("import_module", "__import__") and isinstance(node.args[0].value, str):
            return [node.args[0].value]
    return []


def _package(name: str) -> str | None:
    """The architecture package holding module ``name``, or None."""
    return next((p for p in ARCHITECTURE_PACKAGES if name == p or name.startswith(p + ".")),
                None)


def problems(source: str, where: str, imports_allowed: tuple[str, ...] = ()) -> list[str]:
    """What ``source`` (a module's text) does against the registry rule, one line each
    (``where:line: ...``, by line); ``imports_allowed``: architecture packages this
    module may import."""
    tree = ast.parse(source, where)
    found = set()
    for node in ast.walk(tree):
        for name in _imported(node):
            package = _package(name)
            if package is not None and package not in imports_allowed:
                found.add((node.lineno, f"imports {name}"))
        for name in _names_tested(node):
            found.add((node.lineno, f"tells architectures apart by the name {name!r}"))
    return [f"{where}:{line}: {text}" for line, text in sorted(found)]


def _names_tested(node: ast.AST) -> list[str]:
    """Architecture names ``node`` branches on: an operand of a comparison (``==``,
    ``!=``, ``in``: also inside a tuple, list or set), a key of a dict literal (a table
    by name), a ``case`` pattern."""
    if isinstance(node, ast.Compare):
        operands = [node.left, *node.comparators]
    elif isinstance(node, ast.Dict):
        operands = [k for k in node.keys if k is not None]
    elif isinstance(node, ast.MatchValue):
        operands = [node.value]
    else:
        return []
    found = []
    for op in operands:
        items = op.elts if isinstance(op, ast.Tuple | ast.List | ast.Set) else [op]
        found += [i.value for i in items if isinstance(i, ast.Constant)
                  and isinstance(i.value, str) and i.value in NAMES]
    return found


def _sources() -> dict[str, tuple[Path, tuple[str, ...]]]:
    """Module -> (file, packages it may import): every sim module, and every rtl module
    outside the architecture packages and the registry."""
    testbenches = {tb: w for w in WRAPPERS.values()
                   for tb in (w.testbench, w.register_testbench) if tb is not None}
    out = {}
    for path in sorted((ROOT / "sim").rglob("*.py")):
        module = _module(path, "rvsm.sim", ROOT / "sim")
        wrapper = testbenches.get(module)
        allowed = (wrapper.build.__module__.rpartition(".")[0],) if wrapper else ()
        out[module] = (path, allowed)
    for path in sorted((ROOT / "rtl").rglob("*.py")):
        module = _module(path, "rvsm.rtl", ROOT / "rtl")
        if module == "rvsm.rtl.architectures.registry" or any(
                module == p or module.startswith(p + ".") for p in ARCHITECTURE_PACKAGES):
            continue
        out[module] = (path, ARCHITECTURE_PACKAGES)  # rtl may import them; not name them
    return out


def test_the_walk_covers_sim_and_rtl():
    sources = _sources()
    assert {"rvsm.sim.cli.verify", "rvsm.sim.mutate.checks", "rvsm.sim.regress.plan",
            "rvsm.sim.cosim.long_runs.chunk_twin", "rvsm.rtl.fpga.flow"} <= set(sources)
    assert NAMES >= {"stream", "parallel", "stream_axis"}
    axis_tb = sources["rvsm.sim.cosim.testbenches.tb_axis"][1]
    assert axis_tb == ("rvsm.rtl.ip",)  # the wrapper's testbench, and only its package
    assert sources["rvsm.sim.cosim.testbenches.tb_register_map"][1] == ("rvsm.rtl.ip",)


def test_nothing_outside_the_registry_knows_an_architecture_by_name():
    found = [line for module, (path, allowed) in _sources().items()
             for line in problems(path.read_text(encoding="utf-8"),
                                  str(path.relative_to(ROOT)), allowed)]
    assert not found, ("sim/ and rtl/ reach architectures through the registry's "
                       "values (their capabilities), not by name or import:\n"
                       + "\n".join(found))


def test_the_checker_finds_names_and_imports():
    source = '''"""Docstring naming "stream" and rvsm.rtl.stream is fine."""
import rvsm.rtl.parallel.drive
from rvsm.rtl.stream.schedule import check_beats
from rvsm.rtl import ip


def f(arch, name):
    """A docstring: "stream"."""
    from rvsm.rtl.stream import drive
    import importlib
    importlib.import_module("rvsm.rtl.ip.model")
    if arch.name == "stream" or name in ("parallel",):
        return {"stream_axis": 1}
    return get_architecture("stream"), "--arch stream", "parallel" + name
'''
    found = problems(source, "x.py")
    assert found == [
        "x.py:2: imports rvsm.rtl.parallel.drive",
        "x.py:3: imports rvsm.rtl.stream.schedule",
        "x.py:4: imports rvsm.rtl.ip",
        "x.py:9: imports rvsm.rtl.stream",
        "x.py:11: imports rvsm.rtl.ip.model",
        "x.py:12: tells architectures apart by the name 'parallel'",
        "x.py:12: tells architectures apart by the name 'stream'",
        "x.py:13: tells architectures apart by the name 'stream_axis'",
    ]
    assert problems(source, "x.py", ("rvsm.rtl.ip",)) == [
        f for f in found if "imports rvsm.rtl.ip" not in f]
