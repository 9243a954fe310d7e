"""Drive the fully parallel array in ``amaranth.sim`` and compare its spikes.

:func:`simulate` loads the thresholds through ``cfg``, strobes one step per clock and
reads each step's spikes :attr:`RvsmArray.latency` cycles later; :func:`compare_spikes`
is its expected-output check against :meth:`ArrayContract.run`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.parallel.array import RvsmArray

__all__ = ["compare_spikes", "simulate"]


def simulate(
    contract: ArrayContract,
    codes: np.ndarray,
    thresholds: np.ndarray,
    clear_before: Sequence[int] = (),
    vcd_path: str | None = None,
    mutation: str | None = None,
) -> np.ndarray:
    """Run :class:`RvsmArray` in ``amaranth.sim``; spikes ``(T, S, H, W) int8``.

    Thresholds are loaded through the configuration port, one step is strobed per clock
    and ``clear`` is pulsed for one cycle before each step in ``clear_before``; outputs
    are read :attr:`RvsmArray.latency` cycles after each strobe (checking ``valid``).
    With ``vcd_path`` the run's waveform is written there; ``mutation`` builds a
    deliberately broken array (:mod:`rvsm.rtl.mutations`, ``rvsm mutate``).
    """
    c = contract
    codes = np.asarray(codes, dtype=np.int64)
    thr = np.asarray(thresholds, dtype=np.int64)
    steps = codes.shape[0]
    n_acc = c.num_scales * c.height * c.width
    dut = RvsmArray(c, mutation=mutation)
    out = np.zeros((steps, n_acc), dtype=np.int8)
    clears = {int(t) for t in clear_before}
    shifts = np.arange(c.height * c.width, dtype=object) * c.adc_bits

    async def bench(ctx) -> None:  # noqa: ANN001 - amaranth's SimulatorContext
        for a, value in RvsmArray.threshold_writes(c, thr):
            ctx.set(dut.cfg.we, 1)
            ctx.set(dut.cfg.addr, a)
            ctx.set(dut.cfg.data, value)
            await ctx.tick()
        ctx.set(dut.cfg.we, 0)
        for t in range(steps):
            if t in clears:
                ctx.set(dut.clear, 1)
                await ctx.tick()
                ctx.set(dut.clear, 0)
            ctx.set(dut.codes, int((codes[t].ravel().astype(object) << shifts).sum()))
            ctx.set(dut.strobe, 1)
            await ctx.tick()
            ctx.set(dut.strobe, 0)
            for _ in range(dut.latency - 1):
                await ctx.tick()
            if not ctx.get(dut.valid):
                raise AssertionError(f"valid low {dut.latency} cycle(s) after strobe {t}")
            pos, neg = ctx.get(dut.spike_pos), ctx.get(dut.spike_neg)
            out[t] = [((pos >> a) & 1) - ((neg >> a) & 1) for a in range(n_acc)]

    run_simulation(dut, bench, vcd_path)
    return out.reshape(steps, c.num_scales, c.height, c.width)


def compare_spikes(expected: np.ndarray, got: np.ndarray, max_listed: int = 50) -> dict:
    """Compare spikes ``(T, S, H, W)``: ``compared``, ``mismatches``, ``first_mismatch``
    and up to ``max_listed`` entries of ``mismatch_list`` (``step, scale, row, column,
    expected, got``), in step order."""
    exp, out = np.asarray(expected), np.asarray(got)
    if exp.shape != out.shape:
        raise ValueError(f"spikes of shape {out.shape}, expected {exp.shape}")
    diff = np.argwhere(exp != out)
    listed = [{"step": int(t), "scale": int(s), "row": int(y), "column": int(x),
               "expected": int(exp[t, s, y, x]), "got": int(out[t, s, y, x])}
              for t, s, y, x in diff[:max_listed]]
    return {"compared": int(exp.size), "mismatches": len(diff),
            "first_mismatch": listed[0] if listed else None, "mismatch_list": listed}
