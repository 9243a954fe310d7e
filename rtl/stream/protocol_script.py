"""A protocol script (:class:`ProtocolScript`): what a testbench drives into the streaming
array cycle by cycle and the output it must give, and its file (:func:`save_script`,
:func:`load_script`: ``.npz``, the per-cycle testbench's input). The scripts are made and
checked by :mod:`rvsm.rtl.stream.protocol`, measured by :mod:`.protocol_coverage`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.schedule import OutputBeats, pack_lanes

__all__ = ["SCRIPT_ARRAYS", "ProtocolScript", "Segment", "load_script", "save_script"]


@dataclass(frozen=True)
class Segment:
    """One stream between clears: ``frames`` whole frames, then ``cut`` beats of one
    more frame and a clear (``None``: ``lag`` flush beats instead, then a clear unless
    it is the last segment). ``stall`` is the chance of 1-3 idle cycles before a beat;
    ``idle_after`` idle cycles follow the beats; ``clear_cycles`` cycles of ``clear``,
    with ``codes.valid`` high in them when ``valid_in_clear``."""

    frames: int
    cut: int | None = None
    stall: float = 0.0
    idle_after: int = 1
    clear_cycles: int = 1
    valid_in_clear: bool = False


@dataclass(frozen=True)
class ProtocolScript:
    """A cycle-by-cycle drive of a streaming array and the output it must give.

    Members (``C`` cycles, ``K`` expected output beats):

    * ``valid (C,) bool``, ``codes (C, P) int64``: ``codes.valid`` and the payload's
      lanes in each cycle (junk when not accepted);
    * ``clear (C,) bool``;
    * ``thr_we (C,) bool``, ``thr_scale (C,)``, ``thr_word (C,)`` (``y*G + g``),
      ``thr_data (C, P) int64``: the threshold write of each cycle;
    * ``expected``: :class:`OutputBeats` (``accepted`` unused) of the ``K`` beats;
    * ``expected_cycles (K,)``: the edge after which each is presented;
    * ``expected_steps (K,)``: the step (of ``codes``) each beat belongs to.
    """

    contract: ArrayContract
    lanes: int
    valid: np.ndarray
    codes: np.ndarray
    clear: np.ndarray
    thr_we: np.ndarray
    thr_scale: np.ndarray
    thr_word: np.ndarray
    thr_data: np.ndarray
    expected: OutputBeats
    expected_cycles: np.ndarray
    expected_steps: np.ndarray
    seed: int | None = None

    @property
    def num_cycles(self) -> int:
        """C, the cycles driven."""
        return int(self.valid.shape[0])

    @property
    def geometry(self) -> StreamGeometry:
        """The array's geometry (default banks: the protocol does not depend on them)."""
        return StreamGeometry(self.contract, self.lanes)

    def payload_words(self) -> list[int]:
        """``codes_payload`` of every cycle, lanes packed (lane ``i`` at ``i*N``)."""
        return pack_lanes(self.codes, self.contract.adc_bits)

    def thr_addresses(self) -> list[int]:
        """``thr_addr`` of every cycle: ``(scale << word_bits) | word`` (shared
        thresholds: ``scale``; :meth:`StreamGeometry.threshold_address`)."""
        geo = self.geometry
        return [geo.threshold_address(s, w) for s, w in zip(self.thr_scale, self.thr_word,
                                                            strict=True)]

    def thr_words(self) -> list[int]:
        """``thr_data`` of every cycle, lanes packed (lane ``i`` at ``i*(W-1)``; shared
        thresholds: the one threshold, :meth:`StreamGeometry.threshold_data`)."""
        geo = self.geometry
        if not geo.shared_thresholds:
            return pack_lanes(self.thr_data, self.contract.threshold_bits)
        return [geo.threshold_data(row) for row in self.thr_data]


SCRIPT_ARRAYS = ("valid", "codes", "clear", "thr_we", "thr_scale", "thr_word", "thr_data",
                 "expected_cycles", "expected_steps")


def save_script(path: str | os.PathLike, script: ProtocolScript) -> None:
    """Write ``script`` to ``path`` (``.npz``, atomically): its arrays, the expected
    beats and the contract (:func:`load_script` reads it)."""
    import json
    from dataclasses import asdict

    from rvsm.model.infra.atomic import atomic_path

    e = script.expected
    arrays = {**{k: getattr(script, k) for k in SCRIPT_ARRAYS},
              "exp_rows": e.rows, "exp_groups": e.groups, "exp_last": e.last,
              "exp_spikes": e.spikes, "lanes": np.int64(script.lanes),
              "seed": np.int64(-1 if script.seed is None else script.seed),
              "contract": np.array(json.dumps(asdict(script.contract)))}
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)


def load_script(path: str | os.PathLike) -> ProtocolScript:
    """Read a script written by :func:`save_script` (a file this module wrote: the
    testbench's input, not a user's)."""
    import json

    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in SCRIPT_ARRAYS}
        expected = OutputBeats(z["exp_rows"], z["exp_groups"], z["exp_last"],
                               z["exp_spikes"])
        seed = int(z["seed"])
        raw = json.loads(str(z["contract"]))
        lanes = int(z["lanes"])
    raw["weights"] = tuple(tuple(tuple(int(v) for v in row) for row in k)
                           for k in raw["weights"])
    return ProtocolScript(ArrayContract(**raw), lanes, expected=expected,
                          seed=None if seed < 0 else seed, **arrays)
