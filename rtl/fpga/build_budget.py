"""A point's ``[rtl]`` build judged against its device: lanes, state memory and clock.

:func:`judge_build` is what ``rvsm config check`` adds to the point's own checks: the
lanes must divide the width (:func:`lanes_error` names the divisors nearest the one
asked), the state at those lanes must pack into the device's block RAMs in the
organisation the RTL instantiates (:func:`~rvsm.rtl.fpga.block_ram.pack_state`), and the
clock ``freq_mhz`` must not pass the device's Fmax model at those lanes
(:func:`clock_above_fmax`; ``rvsm verilog`` warns with it before writing an SDC). Each
failure is one line naming the ``rtl.<key>`` (or point field) and the smallest change.
"""

from __future__ import annotations

from rvsm.model.fixed.build_settings import BUILD_SECTION, BuildSettings
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.block_ram import StateLayout, pack_state
from rvsm.rtl.fpga.camera import clock_needed_hz
from rvsm.rtl.fpga.devices import get_budget

__all__ = ["clock_above_fmax", "divisors_near", "judge_build", "lane_clocks", "lanes_error"]

#: Device a build without ``[rtl] device`` is judged on (``rvsm fpga``'s default).
DEFAULT_DEVICE = "ecp5-85"


def divisors_near(width: int, lanes: int, count: int = 6) -> list[int]:
    """The ``count`` divisors of ``width`` nearest ``lanes`` (ascending)."""
    divs = [p for p in range(1, width + 1) if width % p == 0]
    return sorted(sorted(divs, key=lambda p: (abs(p - lanes), p))[:count])


def lanes_error(width: int, lanes: int, field: str = f"{BUILD_SECTION}.lanes") -> str:
    """One line: ``field = lanes`` does not divide ``width``; the divisors near it."""
    near = ", ".join(str(p) for p in divisors_near(width, lanes))
    return (f"{field} = {lanes} does not divide the width {width}; the lane counts near it "
            f"that do: {near}")


def lane_clocks(height: int, width: int, rate_hz: float, count: int = 6) -> str:
    """``"1 (40.0 MHz), 2 (20.0 MHz), ..."``: the ``count`` fewest lane counts dividing
    ``width`` above one lane (beyond one when ``width`` is prime) with the clock each
    needs at ``rate_hz`` steps/s."""
    divs = [p for p in range(1, width + 1) if width % p == 0]
    return ", ".join(f"{p} ({clock_needed_hz(height, width, p, rate_hz) / 1e6:,.1f} MHz)"
                     for p in divs[:count])


def clock_above_fmax(device: str, lanes: int, freq_mhz: float) -> str | None:
    """One line when ``freq_mhz`` passes ``device``'s Fmax model at ``lanes`` lanes (None:
    within it, or the device has no Fmax model)."""
    dev = get_budget(device)
    if dev.timing is None:
        return None
    fmax, how = dev.timing.fmax_mhz(lanes)
    if freq_mhz <= fmax:
        return None
    return (f"{BUILD_SECTION}.freq_mhz = {freq_mhz:g} is above the {device} Fmax model, "
            f"{fmax:.1f} MHz at {lanes} lane(s) ({100 * (freq_mhz / fmax - 1):.0f} % over; "
            f"{how.split(' (')[0]}): set freq_mhz <= {fmax:.0f}")


def judge_build(point: DesignPoint, settings: BuildSettings, source: str) -> str:
    """The one-line verdict of ``point`` built as ``settings`` on its device (default
    :data:`DEFAULT_DEVICE`; its ``package`` named when the point states one, the I/O is
    judged by ``rvsm datasheet``); :class:`RvsmError` when the lanes, memory or clock
    break."""
    device = settings.device or DEFAULT_DEVICE
    lanes = settings.lanes or 1
    if point.width % lanes:
        raise RvsmError(f"{source}: {lanes_error(point.width, lanes)}")
    dev = get_budget(device)
    sp = pack_state(StateLayout.from_contract(point.contract()), lanes, dev, "rtl")
    kind = dev.bram_kind.name
    if sp.unplaceable:
        raise RvsmError(f"{source}: on {device} no memory primitive's ports serve "
                        f"{', '.join(sp.unplaceable)} at {BUILD_SECTION}.lanes = {lanes}")
    if sp.bram > dev.bram:
        raise RvsmError(
            f"{source}: the state needs {sp.bram} of the {dev.bram} {kind} of "
            f"{BUILD_SECTION}.device = {device} ({100 * (sp.bram / dev.bram - 1):.0f} % "
            f"over) at {lanes} lane(s); narrow datapath.accumulator_bits, use threshold."
            "storage = \"shared\", fewer scales, or a larger device")
    if settings.freq_mhz is not None:
        slow = clock_above_fmax(device, lanes, settings.freq_mhz)
        if slow:
            raise RvsmError(f"{source}: {slow}")
    where = f"{device} {settings.package}" if settings.package else device
    verdict = f"fits {where}: state {sp.bram} / {dev.bram} {kind} at {lanes} lane(s)"
    if not dev.placed:
        verdict += (f" ({dev.status}: rvsm fpga does not place {device}"
                    + ("; no Fmax model checks freq_mhz" if dev.timing is None else "") + ")")
    return verdict
