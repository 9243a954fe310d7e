"""The checks of a stimulus file's members (:mod:`rvsm.model.fixed.stimulus`): what a
file may hold before anything in it is used.

Every member is checked against the file's own ``contract``: the contract field by field
(:func:`member_contract`: integer fields in the RTL generator's bounds, known reset and
sensor, 1 to 4 odd square integer kernels), the text members (:func:`member_text`,
:func:`member_meta`), the shapes and integer dtypes of ``codes``, ``thresholds`` and
``spikes`` and their value ranges (:func:`checked_arrays`; codes in the ADC range,
thresholds in the threshold word, spikes in {-1, 0, 1}). A lazily read member is checked
a range of steps at a time as it is read (:func:`value_check`, the
:class:`~rvsm.model.fixed.stimulus_reader.MemberArray` ``check``). Any violation is one
:class:`~rvsm.model.infra.errors.RvsmError` naming the file and the member. Then the
parts against each other (:func:`first_inconsistency`): the point against the contract,
and the expected spikes against what the contract gives from the codes.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Iterator
from typing import Protocol

import numpy as np

from rvsm.model.fixed.contract import SENSORS, ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.stimulus_reader import MemberArray
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.errors import RvsmError

__all__ = ["CONTRACT_LIMITS", "MEMBER_DIMS", "RESETS", "StimulusParts", "check_c_order",
           "checked_arrays", "first_inconsistency", "member_contract", "member_meta",
           "member_text", "value_check"]

#: Dimensions of each member (None: any), checked in the ``.npy`` headers before a member
#: is read (:func:`~rvsm.model.infra.npy_guard.check_npz_members`).
MEMBER_DIMS = {"codes": 3, "thresholds": 3, "spikes": 4, "weights": None,
               "half_widths": None, "contract": 0, "point": 0, "meta": 0,
               "clear_before": None}


def value_check(name: str, c: ArrayContract, source: str
                ) -> Callable[[np.ndarray, int], None]:
    """The check of every range of ``codes`` or ``spikes`` read from a file."""
    top = unsigned_max(c.adc_bits)

    def codes(chunk: np.ndarray, t0: int) -> None:
        if chunk.size and (int(chunk.min()) < 0 or int(chunk.max()) > top):
            raise RvsmError(f"{source}: codes outside the {c.adc_bits}-bit ADC range")

    def spikes(chunk: np.ndarray, t0: int) -> None:
        if chunk.size and (int(chunk.min()) < -1 or int(chunk.max()) > 1):
            raise RvsmError(f"{source}: expected spikes must lie in {{-1, 0, 1}}")

    return codes if name == "codes" else spikes


#: Bounds a stimulus file's contract must keep (what the RTL generator takes).
CONTRACT_LIMITS = {"height": (1, 1 << 16), "width": (1, 1 << 16), "adc_bits": (1, 16),
                    "shift": (0, 62), "accumulator_bits": (2, 62)}
RESETS = ("zero", "subtract")


def member_text(value: np.ndarray, name: str, source: str) -> str:
    """A 0-d string member's text."""
    if value.ndim != 0 or value.dtype.kind not in "US":
        raise RvsmError(f"{source}: {name!r} must be a text scalar, got {value.dtype} "
                        f"{value.shape}")
    return str(value)


def member_meta(value: np.ndarray, source: str) -> dict:
    """The ``meta`` member: a JSON object."""
    try:
        meta = json.loads(member_text(value, "meta", source))
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{source}: 'meta' is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RvsmError(f"{source}: 'meta' must be a JSON object")
    return meta


def check_c_order(name: str, fortran_order: bool, shape: tuple[int, ...],
                  source: str) -> None:
    """A lazily read member must be stored in C order (read a range of steps at a
    time)."""
    if fortran_order and len(shape) > 1:
        raise RvsmError(f"{source}: {name!r} is stored in Fortran order; rvsm stimulus files "
                        f"are C-ordered (write it again with save_stimulus)")


def member_contract(value: np.ndarray, source: str) -> ArrayContract:
    """The file's ``contract`` member, checked field by field."""
    try:
        raw = json.loads(member_text(value, "contract", source))
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{source}: 'contract' is not valid JSON ({exc})") from None
    fields = {f.name for f in dataclasses.fields(ArrayContract)}
    if not isinstance(raw, dict) or set(raw) - fields or \
            fields - {"reset", "sensor", "shared_thresholds"} - set(raw):
        raise RvsmError(f"{source}: 'contract' must be an object with the fields "
                        f"{', '.join(sorted(fields))}")
    for name, (lo, hi) in CONTRACT_LIMITS.items():
        v = raw[name]
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise RvsmError(f"{source}: contract {name} must be an integer in {lo}..{hi}, "
                            f"got {v!r}")
    if not isinstance(raw["signed"], bool) or raw.get("reset", "zero") not in RESETS:
        raise RvsmError(f"{source}: contract signed must be true/false and reset one of "
                        f"{RESETS}")
    if raw.get("sensor", "spike") not in SENSORS:
        raise RvsmError(f"{source}: contract sensor must be one of {SENSORS}, got "
                        f"{raw.get('sensor')!r}")
    shared = raw.get("shared_thresholds")
    if shared is not None and (not isinstance(shared, list) or not all(
            isinstance(v, int) and not isinstance(v, bool) for v in shared)):
        raise RvsmError(f"{source}: contract shared_thresholds must be null or a list of "
                        f"integers, got {shared!r}")
    raw["weights"] = _kernels(raw["weights"], source)
    return ArrayContract(**raw)


def _kernels(value: object, source: str) -> tuple:
    """Integer kernels: 1 to 4 odd square matrices of integers below 2**31 in size."""
    ok = isinstance(value, list) and 1 <= len(value) <= 4
    kernels = []
    for k in value if ok else ():
        n = len(k) if isinstance(k, list) else 0
        ok = ok and n % 2 == 1 and n <= 63 and all(
            isinstance(row, list) and len(row) == n and all(
                isinstance(v, int) and not isinstance(v, bool) and abs(v) < 1 << 31
                for v in row) for row in k)
        if ok:
            kernels.append(tuple(tuple(int(v) for v in row) for row in k))
    if not ok:
        raise RvsmError(f"{source}: contract weights must be 1 to 4 odd square matrices of "
                        f"integers")
    return tuple(kernels)


def checked_arrays(arrays: dict, c: ArrayContract, source: str) -> tuple:
    """``codes``, ``thresholds``, ``spikes`` and ``clear_before`` checked against the
    contract (shapes, integer dtypes, value ranges: those of a :class:`MemberArray` as
    it is read)."""
    codes, thresholds, spikes = arrays["codes"], arrays["thresholds"], arrays["spikes"]
    for name, arr in (("codes", codes), ("thresholds", thresholds), ("spikes", spikes)):
        if arr.dtype.kind not in "iu":
            raise RvsmError(f"{source}: {name!r} must hold integers, got {arr.dtype}")
    t = codes.shape[0] if codes.ndim == 3 else -1
    want = {"codes": (t, c.height, c.width), "thresholds": (c.num_scales, c.height, c.width),
            "spikes": (t, c.num_scales, c.height, c.width)}
    for name, arr in (("codes", codes), ("thresholds", thresholds), ("spikes", spikes)):
        if tuple(arr.shape) != want[name]:
            raise RvsmError(f"{source}: {name!r} has shape {tuple(arr.shape)}, the contract needs "
                            f"{want[name]}")
    if not isinstance(codes, MemberArray):
        value_check("codes", c, source)(codes, 0)
    top = unsigned_max(c.threshold_bits)
    if thresholds.size and (int(thresholds.min()) < 0 or int(thresholds.max()) > top):
        raise RvsmError(f"{source}: thresholds outside 0..{top}")
    if not isinstance(spikes, MemberArray):
        value_check("spikes", c, source)(spikes, 0)
        spikes = spikes.astype(np.int8)
    clears = arrays.get("clear_before", np.zeros(0, np.int64))
    if clears.dtype.kind not in "iu" or clears.ndim != 1:
        raise RvsmError(f"{source}: 'clear_before' must be a 1-d integer array")
    return codes, thresholds.astype(np.int64), spikes, tuple(int(v) for v in clears)


class StimulusParts(Protocol):
    """What :func:`first_inconsistency` reads of a
    :class:`~rvsm.model.fixed.stimulus.Stimulus`."""

    contract: ArrayContract
    point: DesignPoint | None
    thresholds: np.ndarray
    spikes: np.ndarray
    clear_before: tuple[int, ...]

    @property
    def num_steps(self) -> int: ...

    def expected_chunks(self) -> Iterator[tuple[int, np.ndarray, np.ndarray]]: ...


def first_inconsistency(stim: StimulusParts) -> str | None:
    """Where a stimulus's parts disagree with each other, or None: the point's contract
    against ``contract``; the expected ``spikes`` against what ``contract.run`` gives
    from ``codes``, ``thresholds`` and ``clear_before`` (the first step, scale, row and
    column that differ). Costs one fixed-twin run of the stimulus, chunk by chunk
    (bounded memory: a lazy stimulus is read a chunk of steps at a time)."""
    c = stim.contract
    if stim.point is not None:
        try:
            from_point = stim.point.with_size(c.height, c.width).contract()
        except (RvsmError, ValueError, TypeError) as exc:
            return f"its design point cannot make a contract ({exc})"
        if from_point != c:
            return "its design point and its contract disagree"
    want_shape = (stim.num_steps, c.num_scales, c.height, c.width)
    if tuple(stim.spikes.shape) != want_shape:
        return (f"expected spikes have shape {tuple(stim.spikes.shape)}, the codes need "
                f"{want_shape}")
    if stim.thresholds.shape != want_shape[1:]:
        return f"thresholds have shape {stim.thresholds.shape}, need {want_shape[1:]}"
    bad_clear = [t for t in stim.clear_before if not 0 <= t < max(stim.num_steps, 1)]
    if bad_clear:
        return f"clear_before step {bad_clear[0]} is outside 0..{stim.num_steps - 1}"
    count, first = 0, None
    for t0, _, want in stim.expected_chunks():
        got = np.asarray(stim.spikes[t0:t0 + len(want)])
        diff = np.argwhere(want != got)
        count += len(diff)
        if diff.size and first is None:
            b, sc, y, x = (int(v) for v in diff[0])
            first = (t0 + b, sc, y, x, int(got[b, sc, y, x]), int(want[b, sc, y, x]))
    if first is None:
        return None
    t, sc, y, x, have, want_v = first
    return (f"{count} expected spikes do not follow from its codes, thresholds and "
            f"contract; the first at step {t}, scale {sc}, row {y}, column {x} (file "
            f"{have}, contract {want_v})")
