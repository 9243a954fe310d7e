"""``RunSettings``: the one parameter object of ``verify``, ``random_verify`` and
``replay`` (issue 39 deliverable 7: one signature instead of three copies)."""

from __future__ import annotations

import inspect

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.sim.cosim.run_settings import RunSettings
from rvsm.sim.cosim.verify import random_verify, replay, verify


def test_keywords_split_into_settings_and_architecture_options() -> None:
    s = RunSettings.of("icarus", waves=True, harness="auto", chunk_steps=4, lanes=2)
    assert s.arch is get_architecture(DEFAULT_ARCHITECTURE)
    assert (s.sim, s.waves, s.harness, s.chunk_steps) == ("icarus", True, "auto", 4)
    assert dict(s.options) == {"lanes": 2}
    # the keywords give the same settings back: what the command passes down
    assert RunSettings.of(s.sim, **s.keywords()) == s


def test_the_simulator_and_the_harness_are_checked_once() -> None:
    with pytest.raises(RvsmError, match="unknown harness 'fast'"):
        RunSettings.of("icarus", harness="fast")
    with pytest.raises(RvsmError, match="--harness chunk drives the"):
        RunSettings.of("icarus", harness="chunk", arch="parallel")
    with pytest.raises(RvsmError, match="unknown simulator 'nosuchsim'"):
        RunSettings.of("nosuchsim")


def test_the_three_entry_points_share_the_settings_not_copies_of_them() -> None:
    for f in (verify, random_verify, replay):
        params = inspect.signature(f).parameters
        assert "settings" in params and params["settings"].kind is inspect.Parameter.VAR_KEYWORD
        assert not {"waves", "work_dir", "arch", "harness", "chunk_steps"} & set(params)
