"""Which claims judge each sensor: the claim studies, registered by sensor.

The studies stay here in ``sim`` (they run many scenes and write figures); this table
says which of them applies to each registered
:class:`~rvsm.model.sensors.capabilities.Sensor`: the spike camera is judged by the
paper's four claims (SPEC section 6, :mod:`.claims`: ``rvsm table`` for claims 1-3,
``rvsm robustness`` for claim 4), the event sensor by the three claims of SPEC section 7
(:mod:`.event_claims`, ``rvsm events claims``). A new sensor adds its line here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rvsm.model.sensors.capabilities import Sensor
from rvsm.model.sensors.event_sensor import EVENT_SENSOR
from rvsm.model.sensors.spike_camera import SPIKE_CAMERA
from rvsm.sim.studies import claims, event_claims

__all__ = ["CLAIM_STUDIES", "ClaimStudy", "claim_study"]


@dataclass(frozen=True)
class ClaimStudy:
    """The claims one sensor is judged by: where they are stated (``spec``), the
    commands that measure and judge them (``commands``, as typed after ``rvsm``) and the
    judging functions (``judges``: a study's result -> verdicts)."""

    spec: str
    commands: tuple[tuple[str, ...], ...]
    judges: tuple[Callable[..., dict], ...]


#: The claim study of each sensor.
CLAIM_STUDIES: dict[Sensor, ClaimStudy] = {
    SPIKE_CAMERA: ClaimStudy("SPEC section 6, the paper's four claims",
                             (("table",), ("robustness",)),
                             (claims.table_claims, claims.robustness_claim)),
    EVENT_SENSOR: ClaimStudy("SPEC section 7, the event sensor's three claims",
                             (("events", "claims"),), (event_claims.judge,)),
}


def claim_study(sensor: Sensor) -> ClaimStudy:
    """The claims that judge ``sensor``."""
    return CLAIM_STUDIES[sensor]
