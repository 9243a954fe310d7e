"""The sweep's work items: what one worker computes, typed, picklable and self-contained.

A :class:`PointWork` evaluates one sweep task (fixed vs float on one scene); a
:class:`SynthesisWork` is one of the two syntheses of a distinct RTL's lane cost. Each has
a Dask ``key``, a scheduling ``priority`` (syntheses are the longest, so they go first) and
a ``run()`` that returns a JSON-able record. The functions they call are top-level so that
distributed workers only need ``rvsm`` installed (and ``yosys`` for syntheses).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import Any, ClassVar

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.sim.sweep.spec import HardwareSettings, RunSettings, SweepTask


def evaluate_task(task: SweepTask, frames: int, steps_per_frame: int, method: str = "auto",
                  match: str = "gain", threads: int | None = None) -> dict[str, Any]:
    """Fixed vs float on one scene: :func:`~rvsm.model.sensors.cost.quantisation_cost` plus
    ``mse_cost`` (fixed minus float, 8-bit units squared), ``saturation_rate`` (per scale,
    saturated accumulator-steps / (steps * H * W)), ``max_saturation_rate`` and
    ``seconds`` (wall time). ``threads`` caps the numba threads of the twins' fused kernels
    in this process (a local cluster gives each of its ``n`` worker processes
    ``cores // n``, so workers x threads never oversubscribe the cores)."""
    from rvsm.model.scene.loaders import load_scene
    from rvsm.model.sensors.cost import quantisation_cost

    if threads is not None:
        import numba

        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))

    t0 = time.perf_counter()
    scene = load_scene(task.scene, size=task.size, num_frames=frames,
                       steps_per_frame=steps_per_frame)
    rec = quantisation_cost(scene, task.run_point(), method=method, match=match)
    denom = max(1, rec["steps"] * rec["height"] * rec["width"])
    rec["saturation_rate"] = [s / denom for s in rec["saturated"]]
    rec["max_saturation_rate"] = max(rec["saturation_rate"], default=0.0)
    rec["mse_cost"] = rec["mse_fixed"] - rec["mse_float"]
    rec["noise"] = task.noise
    rec["seed"] = task.seed
    rec["seconds"] = time.perf_counter() - t0
    return rec


def hw_point(point: DesignPoint, size: tuple[int, int]) -> DesignPoint:
    """The small array whose RTL is synthesised for ``point`` (noise does not change RTL)."""
    return point.with_size(*size)


def hw_digest(point: DesignPoint, hardware: HardwareSettings) -> str:
    """Cache key of a design's hardware cost: the digest of its RTL contract at
    ``hardware.size`` (RTL sources included), the FPGA flow's sources, the lane counts
    and whether Fmax is measured."""
    from rvsm.rtl.rtl_digest import rtl_digest

    return rtl_digest(hw_point(point, hardware.size).contract(), "stream",
                      {"lane_counts": list(hardware.lanes), "fmax": hardware.fmax})


def synthesise_task(point: DesignPoint, hardware: HardwareSettings, lanes: int
                    ) -> dict[str, Any]:
    """One of the two syntheses of :func:`~rvsm.rtl.fpga.lane_cost.lane_cost`: the
    streaming array of ``point`` at ``hardware.size`` with ``lanes`` lanes (placed and
    routed for Fmax when ``hardware.fmax`` and ``lanes`` is the first lane count). A
    sweep submits the two lane counts as two work items, so they run on two workers."""
    from rvsm.rtl.fpga.lane_cost import lane_synthesis

    fmax = hardware.fmax and lanes == hardware.lanes[0]
    return asdict(lane_synthesis(point, lanes, size=hardware.size, fmax=fmax))


def hw_record(point: DesignPoint, hardware: HardwareSettings,
              syntheses: dict[int, dict[str, Any]]) -> dict[str, Any]:
    """The ``lane_cost`` row of ``point`` from its two :func:`synthesise_task` results
    (keyed by lane count): ``lut4_per_lane``, ``ff_per_lane``, ``lut4_base``, ``fmax_mhz``
    (or None), the memory bits, ``size`` ("HxW"), ``lanes``, ``contract`` (repr) and
    ``seconds`` (both syntheses)."""
    from rvsm.rtl.fpga.lane_cost import LaneSynthesis, combine_lanes

    p1, p2 = hardware.lanes
    cost = combine_lanes(point, hardware.size, LaneSynthesis(**syntheses[p1]),
                         LaneSynthesis(**syntheses[p2]))
    rec = cost.to_dict()
    rec.update(size=f"{hardware.size[0]}x{hardware.size[1]}", lanes=list(hardware.lanes),
               contract=repr(hw_point(point, hardware.size).contract()))
    return rec


@dataclass(frozen=True)
class PointWork:
    """Evaluate one sweep ``task`` with the ``[run]`` settings (:func:`evaluate_task`);
    ``threads`` caps its numba threads (None: the process default)."""

    task: SweepTask
    run_settings: RunSettings
    threads: int | None = None
    priority: ClassVar[int] = 0

    @property
    def key(self) -> str:
        """Unique Dask key."""
        return f"pt-{self.task.point_id}"

    def run(self) -> dict[str, Any]:
        """The task's record (:func:`evaluate_task`)."""
        r = self.run_settings
        return evaluate_task(self.task, r.frames, r.steps_per_frame, r.method, r.match,
                             self.threads)


@dataclass(frozen=True)
class SynthesisWork:
    """Synthesise the design ``point`` whose hardware digest is ``digest`` with ``lanes``
    lanes (:func:`synthesise_task`); a digest's lane cost needs one per lane count."""

    digest: str
    point: DesignPoint
    hardware: HardwareSettings
    lanes: int
    priority: ClassVar[int] = 10

    @property
    def key(self) -> str:
        """Unique Dask key."""
        return f"hw-{self.digest}-p{self.lanes}"

    def run(self) -> dict[str, Any]:
        """The synthesis record (:func:`synthesise_task`)."""
        return synthesise_task(self.point, self.hardware, self.lanes)


#: Anything an executor runs.
WorkItem = PointWork | SynthesisWork
