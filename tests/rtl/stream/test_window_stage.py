"""The window stage (``rtl/stream/window_stage.py``) against its numpy model in
``amaranth.sim``: random frames, stalls and clears; every window the stage registers is
the model's masked window of the position its centre held, and the centre walks the
raster from 0 after each clear, valid from the ``window_lag + 1``-th beat."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.window_stage import WindowStage
from tests.conftest import model_contract


def _cells(word: int, n: int, count: int) -> list[int]:
    return [(word >> (k * n)) & ((1 << n) - 1) for k in range(count)]


def _check_windows(amaranth_sim, geo: StreamGeometry, mutation: str | None = None) -> int:
    """Drive ``WindowStage(geo, mutation)``; assert every window and centre; return the
    positions compared."""
    c, lanes = geo.contract, geo.lanes
    h, w = c.height, c.width
    dut = WindowStage(geo, mutation)
    n, words, cells = c.adc_bits, geo.beats_per_frame, len(geo.window_cells())
    rng = np.random.default_rng(h * w + lanes)
    frames = rng.integers(0, 1 << n, (4, h, w))
    windows = [WindowStage.model(geo, f) for f in frames]
    beats = [int(sum(int(v) << (i * n) for i, v in enumerate(f[y, g * lanes:(g + 1) * lanes])))
             for f in frames for y in range(h) for g in range(geo.groups)]
    checked = []

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        taken = 0          # beats the stage consumed since the last clear
        positions = 0      # positions the centre left since the last clear
        for _ in range(3 * len(beats)):
            clear = rng.random() < 0.01 and taken > 0
            advance = not clear and rng.random() < 0.8 and taken < len(beats)
            ctx.set(dut.ctl.clear, int(clear))
            ctx.set(dut.ctl.advance, int(advance))
            ctx.set(dut.beat, beats[taken] if advance else 0)
            centre = {k: ctx.get(getattr(dut.centre, k))
                      for k in ("valid", "row", "group", "addr", "fresh", "last")}
            assert centre["valid"] == int(taken > geo.window_lag)
            if centre["valid"]:
                a = positions % words
                assert (centre["addr"], centre["row"], centre["group"]) == \
                    (a, a // geo.groups, a % geo.groups)
                assert centre["last"] == int(a == words - 1)
                assert centre["fresh"] == int(positions < words)
            await ctx.tick()
            if clear:
                taken = positions = 0
                continue
            if advance:
                taken += 1
                if centre["valid"]:
                    got = _cells(ctx.get(dut.window.as_value()), n, cells)
                    want = windows[positions // words][positions % words]
                    assert got == list(want), f"position {positions}"
                    checked.append(positions)
                    positions += 1

    amaranth_sim.run(dut, bench)
    return len(checked)


@pytest.mark.parametrize(("model", "h", "w", "lanes"), [
    ("dog4", 6, 8, 2), ("dog2", 5, 6, 3), ("dog4", 6, 4, 4), ("gauss2", 4, 6, 1),
])
def test_windows_follow_the_model(amaranth_sim, model: str, h: int, w: int,
                                  lanes: int) -> None:
    geo = StreamGeometry(model_contract(model, h, w, frac_bits=6), lanes)
    assert _check_windows(amaranth_sim, geo) > geo.beats_per_frame  # over a frame


@pytest.mark.parametrize("mutation", ["stream.top_padding_off_by_one",
                                      "stream.right_padding_off_by_one"])
def test_a_padding_bug_disagrees_with_the_model(amaranth_sim, mutation: str) -> None:
    geo = StreamGeometry(model_contract("dog4", 6, 8, frac_bits=6), 2)
    with pytest.raises(AssertionError, match="position"):
        _check_windows(amaranth_sim, geo, mutation)


def test_the_model_pads_with_zeros_outside_the_frame() -> None:
    geo = StreamGeometry(model_contract("dog2", 4, 4, frac_bits=6), 2)
    frame = np.arange(1, 17).reshape(4, 4)
    window = WindowStage.model(geo, frame)
    cells = geo.window_cells()
    r = geo.radius
    centre = cells.index((r, r))
    assert window[0][centre] == frame[0, 0] and window[-1][cells.index((r, r + 1))] == 16
    corner = cells.index((0, 0)) if (0, 0) in cells else None
    if corner is not None:
        assert window[0][corner] == 0  # above and left of pixel (0, 0)
