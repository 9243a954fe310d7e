"""Sensor-level arithmetic of a streaming pixel array: throughput and state memory.

Throughput. A camera of ``H x W`` pixels sampling at ``step_hz`` (40 kHz for a spike
camera) needs ``H * W * step_hz`` pixel-steps/s (4.0e9 for 250x400). A streaming array
with ``P`` lanes takes ``H * ceil(W / P)`` clock cycles per step, so it needs a clock of
``H * ceil(W / P) * step_hz`` (100 % duty; no blanking), and at a clock ``f`` it needs the
smallest ``P`` dividing ``W`` with that clock ``<= f``.

State memory (exact, at one design point). Per scale and pixel the array keeps an
``A``-bit accumulator and an ``(A-1)``-bit threshold (``A`` = ``accumulator_bits``); the
window needs ``2L`` line buffers of ``W`` ADC codes (``N`` bits), ``L`` the largest
radius of a non-zero quantised weight. Without fixed-pattern noise every accumulator of
a scale has the same threshold, so a design could keep ``S`` threshold registers instead
of a threshold memory; :attr:`StateMemory.thresholds_uniform` says when, and a point with
``threshold.storage = "shared"`` does (:attr:`StateMemory.shared_thresholds`: no threshold
memory bits).

Block RAM. An ECP5 DP16KD holds 18 Kbit as 16Kx1, 8Kx2, 4Kx4, 2Kx9, 1Kx18 or 512x36;
:func:`bram_blocks` counts the blocks one ``depth x width`` memory takes in the best of
those shapes (what a mapper can reach at best; yosys may use more).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.kernels.geometry import kernel_radius
from rvsm.rtl.fpga.devices import DEVICES

__all__ = [
    "BRAM_SHAPES",
    "CAMERA_STEP_HZ",
    "StateMemory",
    "bram_blocks",
    "clock_needed_hz",
    "cycles_per_step",
    "lanes_needed",
    "state_memory",
    "window_radius",
]

#: Sampling steps per second of a real spike camera (SPEC section 1).
CAMERA_STEP_HZ = 40_000.0
#: ``(depth, width)`` configurations of one ECP5 DP16KD block RAM.
BRAM_SHAPES: tuple[tuple[int, int], ...] = (
    (16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36),
)


def cycles_per_step(height: int, width: int, lanes: int) -> int:
    """Clock cycles a ``lanes``-wide raster stream takes per step: ``H * ceil(W / P)``."""
    if lanes < 1:
        raise ValueError(f"lanes must be >= 1, got {lanes}")
    return height * -(-width // lanes)


def clock_needed_hz(height: int, width: int, lanes: int,
                    step_hz: float = CAMERA_STEP_HZ) -> float:
    """Clock (Hz) that ``lanes`` lanes need to keep up with ``step_hz`` steps/s."""
    return cycles_per_step(height, width, lanes) * step_hz


def lanes_needed(height: int, width: int, clock_hz: float,
                 step_hz: float = CAMERA_STEP_HZ) -> int | None:
    """Fewest lanes dividing ``width`` that keep up at ``clock_hz``; ``None`` if none do."""
    for p in range(1, width + 1):
        if width % p == 0 and clock_needed_hz(height, width, p, step_hz) <= clock_hz:
            return p
    return None


def window_radius(contract: ArrayContract) -> int:
    """``L``: the largest Chebyshev radius of a non-zero weight over all scales
    (:func:`~rvsm.model.kernels.geometry.kernel_radius`)."""
    return kernel_radius(contract.weight_arrays)


def bram_blocks(depth: int, width: int) -> int:
    """DP16KD blocks for one ``depth x width`` memory in its best block shape."""
    if depth <= 0 or width <= 0:
        return 0
    return min(math.ceil(depth / d) * math.ceil(width / w) for d, w in BRAM_SHAPES)


@dataclass(frozen=True)
class StateMemory:
    """State bits of an ``S x H x W`` array (see the module docstring); all in bits."""

    num_scales: int
    height: int
    width: int
    accumulator_bits: int
    threshold_bits: int
    adc_bits: int
    radius: int
    thresholds_uniform: bool
    #: ``threshold.storage = "shared"``: one threshold register per scale, no threshold
    #: memory (:attr:`thresholds` is 0 bits; the ``S * (A-1)`` register bits are logic).
    shared_thresholds: bool = False

    @property
    def accumulators(self) -> int:
        """``S * H * W * A`` bits of accumulators."""
        return self.num_scales * self.height * self.width * self.accumulator_bits

    @property
    def thresholds(self) -> int:
        """``S * H * W * (A - 1)`` bits of per-accumulator thresholds (0 when shared)."""
        if self.shared_thresholds:
            return 0
        return self.num_scales * self.height * self.width * self.threshold_bits

    @property
    def line_buffers(self) -> int:
        """``2L * W * N`` bits of line buffers."""
        return 2 * self.radius * self.width * self.adc_bits

    @property
    def total(self) -> int:
        """Accumulators + thresholds + line buffers."""
        return self.accumulators + self.thresholds + self.line_buffers

    def bram_blocks(self, lanes: int) -> dict[str, int]:
        """DP16KD blocks at ``lanes`` lanes (words of ``P`` entries, depth ``H*ceil(W/P)``).

        Accumulators and thresholds: one memory per scale each; line buffers: ``2L``
        memories of depth ``ceil(W/P)`` and word ``P*N``. Best-shape counts
        (:func:`bram_blocks`), so a lower bound for what synthesis maps.
        """
        depth = cycles_per_step(self.height, self.width, lanes)
        per_acc = bram_blocks(depth, lanes * self.accumulator_bits)
        per_thr = 0 if self.shared_thresholds else bram_blocks(depth,
                                                               lanes * self.threshold_bits)
        lines = 2 * self.radius * bram_blocks(-(-self.width // lanes), lanes * self.adc_bits)
        return {"accumulators": self.num_scales * per_acc,
                "thresholds": self.num_scales * per_thr, "line_buffers": lines}

    def fits(self) -> dict[str, dict]:
        """Per device: whether accumulators alone / all state fit its block RAM bits."""
        out = {}
        per_pixel = self.num_scales * (self.accumulator_bits
                                       + (0 if self.shared_thresholds else self.threshold_bits))
        for name, dev in DEVICES.items():
            out[name] = {
                "bram_bits": dev.bram_bits,
                "accumulators_fit": self.accumulators <= dev.bram_bits,
                "all_state_fits": self.total <= dev.bram_bits,
                "pixels_that_fit": max(0, dev.bram_bits - self.line_buffers) // per_pixel,
            }
        return out

    def holders(self) -> list[str]:
        """Devices whose block RAM holds all the state (often none)."""
        return [n for n, f in self.fits().items() if f["all_state_fits"]]

    def to_dict(self) -> dict:
        """JSON-ready fields plus the derived totals and per-device fits."""
        d = asdict(self)
        d.update(accumulator_total=self.accumulators, threshold_total=self.thresholds,
                 line_buffer_total=self.line_buffers, total=self.total,
                 devices=self.fits(), devices_holding_all_state=self.holders())
        return d


def state_memory(contract: ArrayContract, thresholds_uniform: bool = False) -> StateMemory:
    """The :class:`StateMemory` of ``contract``'s array (its own height and width; shared
    threshold registers when the contract has them)."""
    shared = contract.shared_thresholds is not None
    return StateMemory(
        num_scales=contract.num_scales, height=contract.height, width=contract.width,
        accumulator_bits=contract.accumulator_bits,
        threshold_bits=contract.threshold_bits, adc_bits=contract.adc_bits,
        radius=window_radius(contract), thresholds_uniform=thresholds_uniform or shared,
        shared_thresholds=shared,
    )
