"""The registry of sensors, filled in explicitly (one line per sensor).

Every command and study that treats the spike camera and the event sensor differently
looks the sensor up here, once, where its name is read: ``--sensor`` and
``array.sensor`` (:func:`get_sensor`, :func:`sensor_of`) or a file's meta
(:func:`sensor_of_meta`); none compares a sensor's name. Adding a sensor: a kind in
:mod:`rvsm.model.kinds.sensor_kind`, its fixed-twin rules in
:mod:`rvsm.model.fixed.sensor_rules`, its RTL output rule in the arrays' tables, one
:class:`~.capabilities.Sensor` value and one :func:`register` line below
(``docs/architecture.md``, "Where to change what").
"""

from __future__ import annotations

from collections.abc import Mapping

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import SPIKE, SensorKind
from rvsm.model.sensors.capabilities import Sensor
from rvsm.model.sensors.event_sensor import EVENT_SENSOR
from rvsm.model.sensors.spike_camera import SPIKE_CAMERA

__all__ = ["DEFAULT_SENSOR", "SENSORS", "get_sensor", "register", "sensor_names", "sensor_of",
           "sensor_of_meta"]

#: Registered sensors by name, in registration order (the default first).
SENSORS: dict[str, Sensor] = {}
#: The sensor every command simulates unless told otherwise: the spike camera.
DEFAULT_SENSOR = SPIKE.name


def register(sensor: Sensor) -> Sensor:
    """Add ``sensor`` to the registry (its name must be new)."""
    if sensor.name in SENSORS:
        raise ValueError(f"sensor {sensor.name!r} is already registered")
    SENSORS[sensor.name] = sensor
    return sensor


register(SPIKE_CAMERA)
register(EVENT_SENSOR)


def sensor_names() -> tuple[str, ...]:
    """The registered names, the default first (``--sensor`` choices)."""
    return tuple(SENSORS)


def get_sensor(name: str) -> Sensor:
    """The sensor called ``name`` (:class:`RvsmError` naming the valid ones otherwise)."""
    try:
        return SENSORS[name]
    except (KeyError, TypeError):
        raise RvsmError(f"unknown sensor {name!r}; choose one of: "
                        f"{', '.join(SENSORS)}") from None


def sensor_of(kind: SensorKind) -> Sensor:
    """The registered sensor of ``kind`` (a design point's or a contract's)."""
    return get_sensor(kind.name)


def sensor_of_meta(meta: Mapping) -> Sensor:
    """The sensor that wrote a file with this ``meta``: the one whose ``file_kinds``
    holds ``meta["kind"]``, else the default (a spike file: float, fixed or camera)."""
    kind = meta.get("kind")
    for sensor in SENSORS.values():
        if kind in sensor.file_kinds:
            return sensor
    return SENSORS[DEFAULT_SENSOR]
