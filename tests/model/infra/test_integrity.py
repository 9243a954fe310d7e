"""Damage is detected, never read as data: every byte of a spike or stimulus file the
project writes, flipped, gives either the same content or one ``RvsmError`` naming the
damaged part (issue: integrity checks)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rvsm.model.fixed.stimulus import Stimulus, load_stimulus, save_stimulus
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.integrity import header_crc32, verify_npz
from rvsm.model.sensors.files import load_any_spikes
from rvsm.model.spikes.files import write_spikes
from rvsm.sim.cli import main
from tests.fuzzing import fuzz_settings, reader_outcome

SPIKES = np.random.default_rng(0).integers(-1, 2, size=(40, 2, 8, 12)).astype(np.int8)
META = {"model": "dog2", "note": "integrity"}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """The bytes of one ``.h5`` and one ``.npz`` spike file and one stimulus file."""
    folder = tmp_path_factory.mktemp("integrity")
    out = {}
    for suffix in (".h5", ".npz"):
        path = folder / f"ref{suffix}"
        write_spikes(path, SPIKES, META)
        out[suffix] = path.read_bytes()
    out["stimulus"] = _stimulus_bytes(folder)
    return out


def _stimulus_bytes(folder: Path) -> bytes:
    from tests.conftest import model_contract

    contract = model_contract("dog2", 4, 6)
    rng = np.random.default_rng(1)
    codes = rng.integers(0, 1 << contract.adc_bits, (6, 4, 6)).astype(np.uint16)
    thresholds = np.full((contract.num_scales, 4, 6), 40, np.int64)
    spikes = contract.run(codes, thresholds)
    path = folder / "stim.npz"
    save_stimulus(path, Stimulus(codes, thresholds, spikes, contract, None, {"k": 1}))
    return path.read_bytes()


def _load(kind: str, path: Path):
    if kind == "stimulus":
        stim = load_stimulus(path)
        return (stim.codes, stim.thresholds, stim.spikes, stim.meta)
    spikes, meta = load_any_spikes(path)
    meta = {k: v for k, v in meta.items() if k != "versions"}
    return spikes, meta


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y
               for x, y in zip(a, b, strict=True))


def _flip_outcome(kind: str, data: bytes, offset: int, bit: int, path: Path):
    damaged = bytearray(data)
    damaged[offset] ^= 1 << bit
    suffix = ".npz" if kind == "stimulus" else kind
    target = path / f"damaged{suffix}"
    target.write_bytes(bytes(damaged))
    return reader_outcome(lambda: _load(kind, target))


@pytest.mark.parametrize("kind", [".h5", ".npz", "stimulus"])
def test_every_flipped_byte_is_detected_or_harmless(kind, written, tmp_path) -> None:
    """A sweep over the whole file (every 5th byte, two bit positions)."""
    data = written[kind]
    reference = _load(kind, _write(tmp_path / "ref", kind, data))
    detected = 0
    for offset in range(0, len(data), 5):
        for bit in (0, 6):
            outcome = _flip_outcome(kind, data, offset, bit, tmp_path)
            if outcome.ok:
                assert _same(outcome.value, reference), f"byte {offset} bit {bit} read as data"
            else:
                detected += 1
    assert detected > len(data) // 10  # the data itself is covered, not only the padding


@pytest.mark.fuzz
@fuzz_settings
@given(kind=st.sampled_from([".h5", ".npz", "stimulus"]), position=st.floats(0, 1),
       bit=st.integers(0, 7))
def test_flips_anywhere(kind, position, bit, written, tmp_path_factory) -> None:
    data = written[kind]
    offset = min(int(position * len(data)), len(data) - 1)
    folder = tmp_path_factory.mktemp("flip")
    reference = _load(kind, _write(folder / "ref", kind, data))
    outcome = _flip_outcome(kind, data, offset, bit, folder)
    assert not outcome.ok or _same(outcome.value, reference)


def _write(stem: Path, kind: str, data: bytes) -> Path:
    path = stem.with_suffix(".npz" if kind == "stimulus" else kind)
    path.write_bytes(data)
    return path


def test_messages_name_the_damaged_part(written, tmp_path) -> None:
    h5 = tmp_path / "d.h5"
    data = bytearray(written[".h5"])
    data[-100] ^= 0xFF  # inside the last chunk of 'spikes'
    h5.write_bytes(bytes(data))
    with pytest.raises(RvsmError, match=r"dataset 'spikes' steps .* integrity"):
        load_any_spikes(h5)
    npz = tmp_path / "d.npz"
    data = bytearray(written[".npz"])
    data[len(data) // 3] ^= 0x10
    npz.write_bytes(bytes(data))
    with pytest.raises(RvsmError, match=r"spikes\.npy"):
        load_any_spikes(npz)


def test_verify_npz_and_header_checksum(tmp_path) -> None:
    path = tmp_path / "a.npz"
    np.savez_compressed(path, x=np.arange(1000))
    verify_npz(path)
    (tmp_path / "b.npz").write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(RvsmError, match="truncated or corrupt"):
        verify_npz(tmp_path / "b.npz", "spike file")
    assert header_crc32({"a": 1, "b": [2]}) == header_crc32({"b": [2], "a": 1})
    assert header_crc32({"a": 1}) != header_crc32({"a": 2})


def test_evaluate_refuses_a_damaged_h5_from_simulate(tmp_path, capsys) -> None:
    """The issue's case: one flipped byte in a ``.h5`` written by ``rvsm simulate`` was
    evaluated as different spikes with exit 0."""
    h5 = tmp_path / "s.h5"
    small = ["--size", "24x32", "--frames", "4", "--steps-per-frame", "8"]
    assert main(["simulate", "coin", *small, "--model", "dog2", "-o", str(h5)]) == 0
    capsys.readouterr()
    data = bytearray(h5.read_bytes())
    data[-200] ^= 0x04
    h5.write_bytes(bytes(data))
    code = main(["evaluate", str(h5), "coin", *small, "--json"])
    out, err = capsys.readouterr()
    assert code == 2 and "damaged" in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1 and "psnr" not in out.lower()
