"""A point's ``[rtl]`` names checked against the architecture registry and the devices."""

from __future__ import annotations

import pytest

from rvsm.model.fixed.build_settings import BUILD_KEYS, BuildSettings
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.build_settings import check_build_settings


@pytest.mark.parametrize("settings", [
    BuildSettings(),
    BuildSettings(arch="stream", lanes=40, interface="native", freq_mhz=100.0,
                  device="ecp5-85", memory="dp16kd"),
    BuildSettings(interface="axis", fifo_depth=8, lanes=2, memory="inferred"),
    BuildSettings(arch="parallel", device="ecp5-25"),
])
def test_valid_settings_pass(settings):
    check_build_settings(settings, "p.toml")


@pytest.mark.parametrize(("settings", "message"), [
    (BuildSettings(arch="bogus"), "rtl.arch = 'bogus' is not valid; choose one of stream, "
     "parallel"),
    (BuildSettings(interface="pcie"), "rtl.interface = 'pcie' is not valid; choose one of "
     "native, axis"),
    (BuildSettings(arch="parallel", interface="axis"), "rtl.interface = 'axis' is not valid; "
     "arch parallel is offered with native"),
    (BuildSettings(device="ecp5-100"), "rtl.device = 'ecp5-100' is not valid; choose one "
     "of ecp5-25, ecp5-45, ecp5-85, ice40-hx1k, ice40-hx8k, ice40-up5k, gw1n-1, gw1n-4, "
     "gw1n-9, gw2a-18, gw5a-25, gw5ast-138, ccgm1a1"),
    (BuildSettings(memory="bram"), "rtl.memory = 'bram' is not valid; choose one of dp16kd, "
     "inferred"),
    (BuildSettings(arch="parallel", lanes=4), "rtl.lanes = 4 is not valid; arch parallel "
     "with interface native takes no options"),
    (BuildSettings(fifo_depth=8), "rtl.fifo_depth = 8 is not valid; arch stream with "
     "interface native takes lanes"),
])
def test_a_name_no_registry_knows_is_refused(settings, message):
    with pytest.raises(RvsmError) as err:
        check_build_settings(settings, "p.toml")
    assert str(err.value) == f"p.toml: {message}"


def test_every_key_is_checked_here_or_in_the_model():
    assert set(BUILD_KEYS) == {"arch", "lanes", "interface", "freq_mhz", "device", "memory",
                               "fifo_depth"}
