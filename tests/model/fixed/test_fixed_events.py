"""The fixed-point event sensor (SPEC section 7, ``array.sensor = "dvs"``): the log ADC,
the saturating references by hand, the contract with clears, the design point's fields,
the twin against the contract, decoding, and convergence to the float model."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rvsm.model.events.twin import sample_events
from rvsm.model.fixed.adc import log_adc_codes
from rvsm.model.fixed.contract import ArrayContract, FixedEventIntegrator
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.stimulus import (
    load_stimulus,
    make_stimulus,
    save_stimulus,
    write_stimulus,
)
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import load_scene
from rvsm.model.sensors.cost import quantisation_cost, spike_agreement

IDENTITY = (((1,),),)


def test_log_adc() -> None:
    """code = clip(round(ln(max(I, 0) + 1) * 2**f)); 'error' refuses a code beyond the top."""
    b = np.array([[[0.0, 2.0, -5.0, 1e6]]])  # ln(3) * 8 = 8.79
    assert log_adc_codes(b, 6, 3).tolist() == [[[0, 9, 0, 63]]]
    assert log_adc_codes(b, 6, 3, rounding="truncate")[0, 0, 1] == 8
    with pytest.raises(RvsmError, match="beyond the 6-bit code 63"):
        log_adc_codes(b, 6, 3, clip="error")


def test_references_by_hand() -> None:
    """6-bit references (-32..31), threshold 4: capture, one event a step, the reference
    saturating at 31 while the sum runs away, clear recaptures."""
    integ = FixedEventIntegrator(np.full((1, 1, 1), 4), 6)
    got = [int(integ.step(np.full((1, 1, 1), v))[0, 0, 0]) for v in (3, 8, 40, 40, 40)]
    assert got == [0, 1, 1, 1, 1]
    assert int(integ.ref[0, 0, 0]) == 19  # 3 + 4 * 4
    for _ in range(4):
        integ.step(np.full((1, 1, 1), 40))
    assert int(integ.ref[0, 0, 0]) == 31 and int(integ.saturated[0]) == 1
    assert int(integ.step(np.full((1, 1, 1), -40))[0, 0, 0]) == -1
    integ.clear()
    assert int(integ.step(np.full((1, 1, 1), 100))[0, 0, 0]) == 0
    assert int(integ.ref[0, 0, 0]) == 31


def test_contract_with_clears() -> None:
    c = ArrayContract(1, 2, 6, (((0, 1, 0), (1, 2, 1), (0, 1, 0)),), 1, 8, True, "zero",
                      "dvs")
    rng = np.random.default_rng(3)
    codes = rng.integers(0, 64, (12, 1, 2))
    thr = np.array([[[5, 9]]])
    whole = c.run(codes, thr, clear_before=(5,))
    parts = np.concatenate([c.run(codes[:5], thr), c.run(codes[5:], thr)])
    assert np.array_equal(whole, parts)
    assert not whole[0].any() and not whole[5].any()  # capture steps
    stream = c.stream(thr)
    a = stream.run(codes[:5])
    stream.clear()
    assert np.array_equal(np.concatenate([a, stream.run(codes[5:])]), whole)


def test_design_point_fields() -> None:
    p = DesignPoint(sensor="dvs", adc_bits=8, height=8, width=8, model="dog2",
                    scale_contrast=(0.1, 0.3))
    assert p.signed and p.contract().sensor == "dvs"
    assert p.threshold_scale == 2.0 ** (5 + 9)
    assert p.nominal_thresholds().tolist() == [math.ceil(0.1 * 2**14), math.ceil(0.3 * 2**14)]
    with pytest.raises(RvsmError, match="scale_contrast has 1 value"):
        DesignPoint(sensor="dvs", model="dog2", scale_contrast=(0.1,))
    with pytest.raises(RvsmError, match="spike-camera rule"):
        DesignPoint(sensor="dvs", threshold_rule="response")
    fsm = DesignPoint(sensor="dvs", model="fsm", adc_bits=8, height=4, width=4)
    assert fsm.signed  # ON and OFF events for the plain DVS too
    noisy = DesignPoint(sensor="dvs", model="dog2", adc_bits=8, height=4, width=4,
                        noise=True, noise_k=3.0)
    thr = noisy.integer_thresholds()
    theta, _ = noisy.noise_source().fixed_pattern()  # the gain only, no offset
    want = noisy.to_threshold_lsbs(np.maximum(theta * 0.2, 0.0))
    assert np.array_equal(thr, np.clip(want, 1, (1 << 17) - 1))


def test_twin_is_the_contract_and_decodes() -> None:
    scene = load_scene("flyball", size=(16, 20), num_frames=4)
    p = DesignPoint(sensor="dvs", adc_bits=8, model="dog2", height=16, width=20,
                    noise=True)
    stim = make_stimulus(scene, p)
    assert np.array_equal(stim.spikes, p.contract().run(stim.codes, stim.thresholds))
    run = simulate_fixed(scene, p, engine="fused")
    assert np.array_equal(run.spikes, stim.spikes) and np.count_nonzero(run.spikes)
    assert run.meta["kind"] == "events" and run.meta["fixed"] is True


def test_stimulus_files_keep_the_sensor(tmp_path) -> None:
    scene = load_scene("coin", size=(8, 8), num_frames=3)
    p = DesignPoint(sensor="dvs", adc_bits=8, model="gauss2", height=8, width=8)
    path = tmp_path / "s.npz"
    save_stimulus(path, make_stimulus(scene, p))
    assert load_stimulus(path).contract.sensor == "dvs"
    streamed = tmp_path / "w.npz"  # rvsm stimulus's chunked writer: the event twin too
    write_stimulus(streamed, scene, p, chunk_steps=7)
    back = load_stimulus(streamed)
    assert back.first_inconsistency() is None
    assert np.array_equal(back.spikes, load_stimulus(path).spikes)


def test_converges_to_the_float_model() -> None:
    """Finer log ADC and weights, wider references: the fixed events agree ever more with
    the float model's and the PSNR cost shrinks."""
    scene = load_scene("coin", size=(24, 32), num_frames=4)
    base = DesignPoint(sensor="dvs", model="gauss2", height=24, width=32)
    agreements, costs = [], []
    for f, frac, bits in ((3, 6, 8), (5, 9, 10), (9, 14, 14), (12, 16, 16)):
        p = dataclasses.replace(base, adc_log_frac_bits=f, weight_frac_bits=frac,
                                adc_bits=bits, weight_bits=frac + 2,
                                accumulator_bits=bits + frac + 4)
        fixed = simulate_fixed(scene, p).spikes
        flt = sample_events(scene, p.event_config()).events
        agreements.append(spike_agreement(fixed, flt)["agreement"])
        costs.append(abs(quantisation_cost(scene, p)["psnr_cost"]))
    assert agreements == sorted(agreements) and agreements[0] < 0.5 < 0.95 < agreements[-1]
    assert costs[-1] < 0.05 < 1.0 < costs[0]
