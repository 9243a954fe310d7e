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
    BuildSettings(package="CABGA756"),  # on the default device, ecp5-85
    BuildSettings(device="ecp5-25", package="CABGA256"),
    BuildSettings(device="ice40-hx8k", package="CT256"),  # estimate only: its one package
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
    (BuildSettings(device="ecp5-25", package="CABGA756"), "rtl.package = 'CABGA756' is not "
     "valid; rtl.device ecp5-25 comes in CABGA381, CABGA256"),
    (BuildSettings(package="TQ144"), "rtl.package = 'TQ144' is not valid; the default device "
     "ecp5-85 comes in CABGA381, CABGA554, CABGA756"),
    (BuildSettings(device="ice40-hx8k", package="CABGA756"), "rtl.package = 'CABGA756' is "
     "not valid; rtl.device ice40-hx8k comes in CT256"),
    (BuildSettings(device="gw2a-18", package="PG256"), "rtl.package = 'PG256' is not valid; "
     "rtl.device gw2a-18 names no package (estimate only, the package in its part name): "
     "leave rtl.package out"),
])
def test_a_name_no_registry_knows_is_refused(settings, message):
    with pytest.raises(RvsmError) as err:
        check_build_settings(settings, "p.toml")
    assert str(err.value) == f"p.toml: {message}"


def test_every_key_is_checked_here_or_in_the_model():
    assert set(BUILD_KEYS) == {"arch", "lanes", "interface", "freq_mhz", "device", "package",
                               "memory", "fifo_depth"}
