"""The datasheet's parts one by one: headroom and signs that read naturally, counts named
by what they count, only the sensor kind's fields, payload tables that fill their bits and
the ``--commands`` file's checks (the page as a whole: tests/sim/cli/test_datasheet.py and
test_shipped_datasheet.py)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.feasibility import Check
from rvsm.sim.studies.datasheet import budget_text, sensor_fields
from rvsm.sim.studies.datasheet_inputs import load_commands
from rvsm.sim.studies.datasheet_interfaces import field_rows, lane_field_rows
from rvsm.sim.studies.datasheet_summary import margin_text
from rvsm.sim.studies.datasheet_verification import verify_counts
from rvsm.sim.studies.point_quality import better_or_worse


def test_budgets_read_as_spare_or_over_never_a_negative_percentage():
    fits = budget_text(Check("memory", True, 192, 208, "DP16KD", "rtl organisation"))
    assert fits == "fits: 192 of 208 DP16KD, 16 spare (8 % of the budget); rtl organisation"
    over = budget_text(Check("memory", False, 400, 208, "DP16KD"))
    assert over == "BREAKS: 400 of 208 DP16KD, over by 192 (92 %)"
    assert margin_text(115.7, 100.0, "MHz") == "15.7 % headroom (15.7 MHz)"
    assert margin_text(92.0, 100.0, "MHz") == "short by 8.0 % (8.0 MHz)"
    for text in (fits, over, margin_text(92.0, 100.0, "MHz")):
        assert not re.search(r"\(-\d", text)


def test_signs_read_naturally():
    assert better_or_worse(1.399) == "better by 1.399"  # the twin above the float model
    assert better_or_worse(-0.053) == "worse by 0.053"
    assert better_or_worse(0.0004) == "equal"


def test_verify_counts_name_what_they_count():
    v = {"compared": 8_000_000_000, "accumulators": 200_000, "steps": 40_000,
         "expected_spikes": 1_190_471_833}
    assert verify_counts(v) == ("8,000,000,000 accumulator-steps compared (200,000 "
                                "accumulators x 40,000 steps), 1,190,471,833 of them spikes")
    assert verify_counts({"compared": 12}) == "12 accumulator-steps compared"


def test_only_the_sensor_kinds_fields():
    spike = {f.path for f in sensor_fields("spike")}
    dvs = {f.path for f in sensor_fields("dvs")}
    only_dvs = {"adc.log_frac_bits", "threshold.contrast", "threshold.scale_contrast"}
    assert not spike & only_dvs and only_dvs <= dvs
    assert {"adc.bits", "threshold.phi", "datapath.accumulator_bits"} <= spike & dvs


def _covered(rows: list[str], width: int) -> list[int]:
    """Each bit of a ``width``-bit payload: how many rows of a field table claim it."""
    hits = [0] * width
    for row in rows:
        m = re.match(r"\| \[(\d+)(?::(\d+))?\] \|", row)
        hi, lo = int(m.group(1)), int(m.group(2) or m.group(1))
        for b in range(lo, hi + 1):
            hits[b] += 1
    return hits


def test_payload_tables_fill_their_bits():
    fields = [{"name": "row", "offset": 0, "width": 3, "desc": "row"},
              {"name": "last", "offset": 3, "width": 1, "desc": "last"},
              {"name": "pos", "offset": 4, "width": 4, "desc": "spikes"}]
    assert _covered(field_rows(fields), 8) == [1] * 8
    assert field_rows(fields)[1] == "| [3] | `last` | 1 | last |"
    few = lane_field_rows(3, 7, 7, "ADC code")  # every lane listed
    assert _covered(few, 21) == [1] * 21
    many = lane_field_rows(40, 8, 7, "ADC code")  # first, formula, last, padding
    assert many[0] == "| [6:0] | `code0` | 7 | ADC code of lane 0 |"
    assert many[2] == "| [318:312] | `code39` | 7 | ADC code of lane 39 |"
    assert "[8i+6:8i]" in many[1] and many[3].startswith("| [8i+7] | padding")


def test_commands_file_refuses_cut_or_unsourced_commands(tmp_path: Path):
    f = tmp_path / "commands.toml"
    f.write_text('[verify]\ncommand = "rvsm verify flyball --steps 40000 --json"\n'
                 'source = "docs/fpga.md quotes it"\n')
    assert load_commands(f) == {"verify": ("rvsm verify flyball --steps 40000 --json",
                                           "docs/fpga.md quotes it")}
    for text, message in (('[verify]\ncommand = "rvsm verify ..."\nsource = "x"\n', "whole"),
                          ('[verify]\ncommand = "rvsm verify a"\n', "source"),
                          ('[other]\ncommand = "rvsm a"\nsource = "x"\n', "unknown table")):
        f.write_text(text)
        with pytest.raises(RvsmError, match=message):
            load_commands(f)
