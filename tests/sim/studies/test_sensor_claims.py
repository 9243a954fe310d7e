"""The claim studies registered by sensor: every sensor is judged by claims, and the
commands that measure them exist."""

from __future__ import annotations

from rvsm.model.sensors.registry import SENSORS
from rvsm.sim.cli.main import build_parser
from rvsm.sim.studies import claims, event_claims
from rvsm.sim.studies.sensor_claims import CLAIM_STUDIES, claim_study


def test_every_registered_sensor_has_its_claims():
    assert set(CLAIM_STUDIES) == set(SENSORS.values())
    assert claim_study(SENSORS["spike"]).judges == (claims.table_claims,
                                                    claims.robustness_claim)
    assert claim_study(SENSORS["dvs"]).judges == (event_claims.judge,)
    assert "section 6" in claim_study(SENSORS["spike"]).spec
    assert "section 7" in claim_study(SENSORS["dvs"]).spec


def _subcommand(parser, words):
    """The parser of ``rvsm <words>`` (KeyError when there is none)."""
    for word in words:
        parser = parser._subparsers._group_actions[0].choices[word]  # noqa: SLF001
    return parser


def test_the_commands_of_each_claim_study_exist():
    parser = build_parser()
    for study in CLAIM_STUDIES.values():
        for command in study.commands:
            assert _subcommand(parser, command).prog.endswith(" ".join(command))
