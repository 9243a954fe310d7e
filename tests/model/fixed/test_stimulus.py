"""Stimulus files: checked before the RTL is blamed, and a reader that cannot be broken.

``first_inconsistency`` finds a hand-edited expectation (step, scale, row, column);
``load_stimulus`` turns every damaged, truncated or hand-made file into one ``RvsmError``
(fuzzed with ``hypothesis``: valid extremes round-trip, corruptions are refused)."""

from __future__ import annotations

import dataclasses
import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.stimulus import Stimulus, load_stimulus, save_stimulus
from rvsm.model.infra.errors import RvsmError
from tests.conftest import model_contract
from tests.fuzzing import assert_no_partial_files, corrupted, fuzz_settings, reader_outcome

MODELS = ("fsm", "dog1", "dog4", "gauss2", "gauss4")


def _stimulus(model: str = "dog2", h: int = 4, w: int = 6, steps: int = 6, seed: int = 1,
              acc_bits: int = 10, clears: tuple[int, ...] = ()) -> Stimulus:
    contract = model_contract(model, h, w, acc_bits=acc_bits)
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << contract.adc_bits, (steps, h, w)).astype(np.uint16)
    top = (1 << contract.threshold_bits) - 1
    thresholds = rng.integers(1, min(top, 60) + 1, (contract.num_scales, h, w))
    spikes = contract.run(codes, thresholds, clears)
    return Stimulus(codes, thresholds.astype(np.int64), spikes, contract, None, {"seed": seed},
                    clears)


def test_a_consistent_stimulus_has_no_inconsistency() -> None:
    assert _stimulus().first_inconsistency() is None
    assert _stimulus(clears=(2, 4)).first_inconsistency() is None


def test_an_edited_expectation_is_named() -> None:
    stim = _stimulus()
    wrong = stim.spikes.copy()
    wrong[3, 1, 2, 5] = 1 if wrong[3, 1, 2, 5] != 1 else -1
    text = dataclasses.replace(stim, spikes=wrong).first_inconsistency()
    assert text and "step 3, scale 1, row 2, column 5" in text
    fixed = dataclasses.replace(stim, spikes=wrong).with_recomputed_expectation()
    np.testing.assert_array_equal(fixed.spikes, stim.spikes)


def test_a_point_that_disagrees_with_the_contract_is_named() -> None:
    stim = _stimulus()
    point = default_design_point().with_size(4, 6)  # dog4, not the file's dog2 contract
    assert "disagree" in dataclasses.replace(stim, point=point).first_inconsistency()
    ok = dataclasses.replace(stim, contract=point.contract(), point=point)
    assert "shape" in ok.first_inconsistency()  # 2-scale spikes under a 4-scale contract
    ok = dataclasses.replace(ok, thresholds=np.full((4, 4, 6), 30, np.int64))
    ok = dataclasses.replace(ok, spikes=np.zeros((6, 4, 4, 6), np.int8))
    assert "do not follow" in ok.first_inconsistency()
    assert ok.with_recomputed_expectation().first_inconsistency() is None


def test_clears_outside_the_stream_are_named() -> None:
    stim = dataclasses.replace(_stimulus(), clear_before=(9,))
    assert "clear_before step 9" in stim.first_inconsistency()


# --- the reader, fuzzed ---------------------------------------------------------------

@st.composite
def stimuli(draw: st.DrawFn) -> Stimulus:
    """Valid extremes: one pixel, one step, every model, narrow and wide accumulators."""
    model = draw(st.sampled_from(MODELS))
    h = draw(st.integers(1, 5))
    w = draw(st.integers(1, 5))
    steps = draw(st.integers(1, 6))
    acc = draw(st.sampled_from([4, 10, 24]))
    clears = tuple(draw(st.lists(st.integers(1, max(steps - 1, 1)), max_size=2)))
    return _stimulus(model, h, w, steps, draw(st.integers(0, 3)), acc,
                     clears if steps > 1 else ())


def _same(a: Stimulus, b: Stimulus) -> bool:
    def meta(m: dict) -> dict:
        return {k: v for k, v in m.items() if k != "versions"}

    return (a.contract == b.contract and meta(a.meta) == meta(b.meta)
            and a.clear_before == b.clear_before
            and all(np.array_equal(getattr(a, k), getattr(b, k))
                    for k in ("codes", "thresholds", "spikes")))


@pytest.mark.fuzz
@fuzz_settings
@given(stim=stimuli())
def test_valid_extremes_round_trip(stim: Stimulus, tmp_path_factory) -> None:
    folder = tmp_path_factory.mktemp("stim")
    path = folder / "s.npz"
    save_stimulus(path, stim)
    outcome = reader_outcome(lambda: load_stimulus(path))
    assert outcome.ok, outcome.message
    assert _same(outcome.value, stim) and outcome.value.first_inconsistency() is None
    assert_no_partial_files(folder)


@pytest.fixture(scope="module")
def stimulus_bytes(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("ref") / "s.npz"
    save_stimulus(path, _stimulus(clears=(3,)))
    return path.read_bytes()


@pytest.mark.fuzz
@fuzz_settings
@given(data=st.data())
def test_damaged_files_are_refused_in_one_line(data, stimulus_bytes, tmp_path_factory) -> None:
    damaged = data.draw(corrupted(stimulus_bytes))
    path = tmp_path_factory.mktemp("bad") / "s.npz"
    path.write_bytes(damaged)
    outcome = reader_outcome(lambda: load_stimulus(path))
    if outcome.ok:  # a damaged byte the format does not read (zip padding, timestamps)
        assert _same(outcome.value, load_stimulus(_ref(path, stimulus_bytes)))


def _ref(path: Path, data: bytes) -> Path:
    ref = path.with_name("ref.npz")
    ref.write_bytes(data)
    return ref


#: Replacements of one member: wrong dtypes, shapes, values, JSON and types.
MEMBER_EDITS = {
    "codes": [np.zeros((2, 4), np.uint16), np.full((6, 4, 6), 70000, np.int64),
              np.zeros((6, 4, 6), np.float64), np.full((6, 4, 6), -1, np.int16),
              np.array("text")],
    "thresholds": [np.zeros((1, 4, 6), np.int64), np.full((2, 4, 6), 1 << 40, np.int64),
                   np.full((2, 4, 6), np.nan)],
    "spikes": [np.zeros((6, 2, 4, 6), np.float32), np.full((6, 2, 4, 6), 5, np.int8),
               np.zeros((7, 2, 4, 6), np.int8)],
    "contract": [np.array("{"), np.array("[]"), np.array(json.dumps({"height": 4})),
                 np.zeros(3), np.array("null")],
    "meta": [np.array("[1]"), np.array("{"), np.zeros(2)],
    "point": [np.array("[adc\nbits = 'x'"), np.zeros(1)],
    "clear_before": [np.zeros((2, 2), np.int64), np.array([0.5])],
}


def _edited(data: bytes, member: str, value: np.ndarray | None) -> bytes:
    """``data`` with ``member`` replaced by ``value`` (None: removed), or a new member."""
    source = zipfile.ZipFile(io.BytesIO(data))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as target:
        for info in source.infolist():
            if info.filename != f"{member}.npy":
                target.writestr(info, source.read(info))
        if value is not None:
            buf = io.BytesIO()
            np.save(buf, value, allow_pickle=False)
            target.writestr(f"{member}.npy", buf.getvalue())
    return out.getvalue()


EDITS = [(m, i) for m, values in MEMBER_EDITS.items() for i in range(len(values))]


@pytest.mark.fuzz
@fuzz_settings
@given(edit=st.sampled_from(EDITS + [("codes", None), ("contract", None),
                                      ("extra", "value")]))
@example(edit=("contract", 2))
def test_hand_made_members_are_refused_in_one_line(edit, stimulus_bytes,
                                                   tmp_path_factory) -> None:
    member, index = edit
    if index is None:
        value = None
    elif index == "value":
        value = np.arange(3)
    else:
        value = MEMBER_EDITS[member][index]
    path = tmp_path_factory.mktemp("edit") / "s.npz"
    path.write_bytes(_edited(stimulus_bytes, member, value))
    outcome = reader_outcome(lambda: load_stimulus(path))
    if member == "extra":  # an extra member is ignored
        assert outcome.ok, outcome.message
    else:
        assert not outcome.ok, f"{member} edit {index} was read"


def test_refusals_name_the_problem(stimulus_bytes, tmp_path) -> None:
    path = tmp_path / "s.npz"
    cases = {("codes", 1): "ADC range", ("contract", 2): "fields",
             ("spikes", 1): "-1, 0, 1", ("thresholds", 1): "thresholds outside",
             ("codes", 2): "integers", ("meta", 0): "JSON object"}
    for (member, index), words in cases.items():
        path.write_bytes(_edited(stimulus_bytes, member, MEMBER_EDITS[member][index]))
        with pytest.raises(RvsmError, match=words):
            load_stimulus(path)


def test_a_member_that_is_not_an_array_is_refused(stimulus_bytes, tmp_path) -> None:
    """Found by ``make fuzz``: a member whose bytes are not ``.npy`` data (numpy returns
    them as raw ``bytes``) was used as an array (``AttributeError``)."""
    source = zipfile.ZipFile(io.BytesIO(stimulus_bytes))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as target:
        for info in source.infolist():
            name = info.filename.removesuffix(".npy")
            data = b"not npy data" if name == "contract" else source.read(info)
            target.writestr(name, data)
    path = tmp_path / "s.npz"
    path.write_bytes(out.getvalue())
    outcome = reader_outcome(lambda: load_stimulus(path))
    assert not outcome.ok
