"""Images from events (:mod:`rvsm.model.events.reconstruction`): responses from
references and counts, chunked reading, the plain DVS by hand, scores."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rvsm.model.events.config import EventConfig
from rvsm.model.events.reconstruction import (
    capture_references,
    config_from_meta,
    evaluate_events,
    event_images,
    event_responses,
    scored_event_steps,
)
from rvsm.model.events.twin import sample_events
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import load_scene
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.source import array_source


def test_plain_dvs_image_by_hand() -> None:
    """I: 0 -> e^0.5 - 1 at one pixel; after two ON events of C = 0.2 the decoded log is
    0.4, the image e^0.4 - 1 (the last 0.1 is below the threshold)."""
    frames = np.zeros((3, 2, 2))
    frames[1:, 0, 0] = math.exp(0.5) - 1.0
    scene = Scene("step", frames, steps_per_frame=4, hold=True)
    cfg = EventConfig("fsm")
    train = sample_events(scene, cfg)
    refs = capture_references(scene, cfg)
    assert np.array_equal(refs, train.references)
    r = event_responses(array_source(train.events, train.meta), refs, cfg.contrasts,
                        np.array([8]))
    img = event_images(r, cfg)[0]
    assert img[0, 0] == pytest.approx(math.exp(0.4) - 1.0)
    assert np.all(img.ravel()[1:] == 0)


def test_responses_do_not_depend_on_chunks() -> None:
    scene = load_scene("flyball", size=(16, 24), num_frames=5)
    cfg = EventConfig("dog2")
    train = sample_events(scene, cfg)
    src = array_source(train.events, train.meta)
    steps = np.array([3, 10, 11, 39])
    a = event_responses(src, train.references, cfg.contrasts, steps, chunk_steps=4)
    b = event_responses(src, train.references, cfg.contrasts, steps, chunk_steps=1000)
    assert np.array_equal(a, b)
    want = train.references + cfg.contrasts[:, None, None] * \
        np.cumsum(train.events, axis=0)[steps]
    assert np.allclose(a, want)


def test_evaluate_events_scores_and_checks_shape() -> None:
    scene = load_scene("coin", size=(24, 32), num_frames=4)
    for model in ("fsm", "gauss2"):
        train = sample_events(scene, EventConfig(model, contrast=0.05))
        result = evaluate_events(array_source(train.events, train.meta), scene)
        assert result["psnr"] > 25 and 0.5 < result["ssim"] <= 1
        assert result["num_scored"] == len(scored_event_steps(scene))
    other = load_scene("coin", size=(24, 32), num_frames=5)
    with pytest.raises(RvsmError, match="do not match"):
        evaluate_events(array_source(train.events, train.meta), other)
    with pytest.raises(RvsmError, match="meta does not describe"):
        config_from_meta({"kind": "events"})
