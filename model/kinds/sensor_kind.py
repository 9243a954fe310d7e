"""What a sensor is, as a value: the spike camera or the event sensor (SPEC sections 5, 7).

A :class:`SensorKind` states the facts the lower packages and the RTL branch on, so none
of them compares a sensor's name: its ``name`` (``array.sensor`` in a design point,
``--sensor`` on the command line, ``ArrayContract.sensor``) and its :class:`Output`,
what one accumulator emits per step. The output is also the RTL's output rule: the
fixed-point contract picks its integrator by it
(:func:`rvsm.model.fixed.contract.make_integrator`) and each RTL array its tail, each
through a table keyed by :class:`Output`.

The layering (``docs/architecture.md``): this module is the bottom of the sensor axis.
:mod:`rvsm.model.fixed.sensor_rules` holds what the fixed twin does per kind (ADC law,
threshold units, fixed-pattern noise, the float model it approximates);
:mod:`rvsm.model.sensors` composes the registered
:class:`~rvsm.model.sensors.capabilities.Sensor` values (float twin, decoder, file
kinds) from the packages below. A name is turned into a kind once, where it is read:
:func:`sensor_kind`.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from rvsm.model.infra.errors import RvsmError

__all__ = ["DVS", "SENSOR_KINDS", "SENSOR_NAMES", "SPIKE", "Output", "SensorKind",
           "sensor_kind"]


class Output(enum.Enum):
    """What an accumulator emits per step: the twin's output and the RTL's output rule.

    ``SPIKES``: integrate and fire (contract steps 3-5: saturating accumulator, compare
    with the threshold, fire +1 / -1, reset). ``EVENTS``: a reference per accumulator,
    captured at the first step after a clear, then ON (+1) / OFF (-1) events whenever the
    shifted sum moves a threshold away from it (the reference follows by one threshold).
    """

    SPIKES = "spikes"
    EVENTS = "events"


@dataclass(frozen=True)
class SensorKind:
    """One kind of sensor: ``name`` (the text of ``array.sensor`` / ``--sensor``),
    ``noun`` (for messages), ``output`` (:class:`Output`), ``signals`` and ``negative``
    (what a run's summary calls its outputs and the -1 ones), and what follows a model's
    name in reports: ``suffix`` (``rvsm config check``, ``rvsm cost``) and ``tag``
    (``rvsm evaluate``), both empty for the spike camera."""

    name: str
    noun: str
    output: Output
    signals: str
    negative: str
    suffix: str
    tag: str


#: The spike camera: integrate-and-fire accumulators (SPEC section 5).
SPIKE = SensorKind("spike", "spike camera", Output.SPIKES, "spikes", "negative", "", "")
#: The event sensor, RVSM-DVS (SPEC section 7): references and ON/OFF events.
DVS = SensorKind("dvs", "event sensor", Output.EVENTS, "events", "OFF", " (event sensor)",
                 " (dvs)")

#: Every kind by name, the default (the spike camera) first.
SENSOR_KINDS: dict[str, SensorKind] = {k.name: k for k in (SPIKE, DVS)}
#: The names ``array.sensor`` and ``--sensor`` take.
SENSOR_NAMES: tuple[str, ...] = tuple(SENSOR_KINDS)


def sensor_kind(name: str) -> SensorKind:
    """The kind called ``name`` (:class:`RvsmError` naming the valid ones otherwise)."""
    try:
        return SENSOR_KINDS[name]
    except (KeyError, TypeError):
        raise RvsmError(f"sensor must be one of {SENSOR_NAMES}, got {name!r}") from None
