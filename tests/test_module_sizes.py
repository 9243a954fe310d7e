"""Hand-written modules stay small (issue 39, deliverable 7): no module of ``model/``,
``rtl/`` or ``sim/`` is over :data:`MAX_LINES` lines, one concept a module.

The only exceptions are the modules the project generates: the unrolled numba kernels
that ``python -m rvsm.model.sampling.kernel_generator`` writes (its ``TARGETS``; their
text is checked up to date by ``tests/model/sampling/test_fused.py``, and splitting them
would change numba's per-module caches for nothing a reader gains: nobody edits them).
They are read from the generator, not listed here, and each must say it is generated.
"""

from __future__ import annotations

from pathlib import Path

from rvsm.model.sampling.kernel_generator import TARGETS

ROOT = Path(__file__).resolve().parents[1]
#: The most lines a hand-written module may have.
MAX_LINES = 400
#: Generated modules (relative to the repository root) and why each may be longer.
GENERATED = {Path("model", *parts): "written by rvsm.model.sampling.kernel_generator"
             for parts in TARGETS}


def _lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def _modules() -> list[Path]:
    return sorted(p.relative_to(ROOT) for folder in ("model", "rtl", "sim")
                  for p in (ROOT / folder).rglob("*.py") if "__pycache__" not in p.parts)


def test_no_hand_written_module_is_over_the_limit():
    over = [f"{p}: {_lines(ROOT / p)} lines" for p in _modules()
            if p not in GENERATED and _lines(ROOT / p) > MAX_LINES]
    assert not over, ("split these by concept (one concept a module; docs/architecture.md "
                      "names each): " + "; ".join(over))


def test_the_exceptions_are_generated_modules_that_exist():
    assert GENERATED  # the generator's targets: the kernels
    for path in GENERATED:
        head = (ROOT / path).read_text(encoding="utf-8")[:400]
        assert "do not edit" in head and "kernel_generator" in head, path


def test_the_walk_sees_the_large_packages():
    modules = set(_modules())
    assert {Path("model/fixed/contract.py"), Path("rtl/fpga/flow.py"),
            Path("sim/sweep/spec.py")} <= modules
    assert len(modules) > 300
