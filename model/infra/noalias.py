"""Numba functions compiled with ``noalias`` pointer arguments.

``@njit(pipeline_class=NoAliasCompiler)`` compiles a function with numba's ``noalias``
flag (numba's default pipeline otherwise): every pointer argument, so each array
argument's data, is marked ``noalias``. LLVM then knows that loads through one array
argument and stores through another never touch the same memory, and vectorises a loop
over them without runtime alias checks (a loop reading 45 rows and writing 8 otherwise
carries hundreds of pointer comparisons; with them, rows of 128 columns or fewer ran 2-5x
slower per pixel). Only for functions whose array arguments are distinct allocations, never
overlapping views of one array: :mod:`rvsm.model.events.ladder_kernels`,
:func:`rvsm.model.sampling.fused._step_rows`. Results do not
change (no reassociation: ``noalias`` only removes the checks). Imports numba: import it
after :mod:`rvsm.model` (:mod:`.simd` chooses the vector width before numba loads).
"""

from __future__ import annotations

from numba.core.compiler import Compiler

__all__ = ["NoAliasCompiler"]


class NoAliasCompiler(Compiler):
    """Numba's default compiler pipeline with the ``noalias`` flag set."""

    def define_pipelines(self):
        self.state.flags.noalias = True
        return super().define_pipelines()
