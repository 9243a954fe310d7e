"""A design point as TOML: the file format of :class:`DesignPoint`, derived from its fields.

Sections and keys come from the field declarations (:data:`FIELDS`, in file order);
:func:`design_point_toml` writes every field with its comment and valid values (what
``rvsm config new`` prints); loading refuses unknown sections and keys and reports any
refusal as ``<file>: <section.key> ...``. Missing keys take the defaults.

A point file may also hold an ``[rtl]`` table: how the point is built
(:class:`~rvsm.model.fixed.build_settings.BuildSettings`), not a field of the point.
Loading checks it and leaves it out of the :class:`DesignPoint`
(:func:`load_point_file` returns both); :func:`new_point_toml` shows it commented out.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

import tomli_w

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from rvsm.model.fixed.build_settings import BUILD_SECTION, BuildSettings, build_settings_toml
from rvsm.model.fixed.design_point import FIELDS, DesignPoint
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError, shown
from rvsm.model.infra.text_files import read_utf8_text
from rvsm.model.sampling.thresholds import DEFAULT_CALIBRATION_SCENE

__all__ = [
    "SECTION_COMMENTS", "design_point_toml", "from_toml_dict", "load_design_point",
    "load_point_file", "new_point_toml", "parse_design_point", "parse_point_file",
    "save_design_point", "to_toml_dict",
]

#: What each section computes (the per-key comments come from the field declarations).
SECTION_COMMENTS = {
    "array": "Array size (pixels) and sampling model.",
    "adc": "code = clip(q(b * (2**bits - 1) / full_scale), 0, 2**bits - 1), b = brightness +\n"
    "# dark current (8-bit units). rounding: truncate (floor) | round-half-up (floor(x+0.5)).\n"
    "# clip: saturate (pin to 0 / 2**bits-1) | error (refuse inputs outside 0..full_scale).",
    "weights": "w = q(K * 2**frac_bits), signed two's complement of `bits` bits;\n"
    "# rounding: truncate (floor) | round-half-up. A weight that overflows is refused.",
    "datapath": "Per-step sum >> shift (arithmetic: floor division by 2**shift), then added to\n"
    "# a signed, saturating accumulator of accumulator_bits bits.",
    "threshold": "phi (8-bit brightness units; scale_phi = [..] overrides it per scale) maps to\n"
    "# q(phi * (2**adc.bits-1)/adc.full_scale * 2**weights.frac_bits / 2**datapath.shift)\n"
    "# LSBs; rounding: ceil (exact for acc >= phi) | round-half-up | truncate.\n"
    "# reset: zero (acc = 0 after a spike) | subtract (acc -= +-threshold).",
    "noise": "SPEC section 3 noise (dark current before the ADC, fixed pattern folded into\n"
    "# the integer thresholds), intensity k, numpy seed (same seed as the float model).",
}
SECTIONS: tuple[str, ...] = tuple(dict.fromkeys(f.section for f in FIELDS))
#: What an unset optional choice looks like, commented out, in ``rvsm config new``.
_EXAMPLES = {"threshold_rule": "response", "calibration_scene": DEFAULT_CALIBRATION_SCENE,
             "noise_preset": "paper"}


def _toml_value(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


def to_toml_dict(point: DesignPoint) -> dict[str, dict[str, Any]]:
    """Nested ``{section: {key: value}}`` form; an unset ``scale_phi`` is omitted."""
    out: dict[str, dict[str, Any]] = {}
    for f in FIELDS:
        value = getattr(point, f.name)
        if value is not None:
            out.setdefault(f.section, {})[f.key] = _toml_value(value)
    return out


def from_toml_dict(data: dict[str, Any], source: str = "design point",
                   also: tuple[str, ...] = ()) -> DesignPoint:
    """Build from the nested TOML form; unknown sections or keys are refused (``also``:
    sections the caller reads itself, named among the valid ones in the refusal)."""
    known = {(f.section, f.key): f.name for f in FIELDS}
    kwargs: dict[str, Any] = {}
    for sec, table in data.items():
        if sec not in SECTIONS or not isinstance(table, dict):
            raise RvsmError(
                f"{source}: unknown section [{shown(sec)}]; valid sections: "
                f"{', '.join(sorted((*SECTIONS, *also)))}"
            )
        for key, value in table.items():
            if (sec, key) not in known:
                valid = ", ".join(f.key for f in FIELDS if f.section == sec)
                raise RvsmError(f"{source}: unknown key {shown(sec)}.{shown(key)}; "
                                f"[{shown(sec)}] takes {valid}")
            kwargs[known[(sec, key)]] = value
    try:
        return DesignPoint(**kwargs)
    except RvsmError as exc:
        raise RvsmError(f"{source}: {exc}") from None


def design_point_toml(point: DesignPoint) -> str:
    """The point as a commented TOML document (what ``rvsm config new`` prints).

    Every key is preceded by its declared comment and valid values; an unset
    ``scale_phi`` is shown commented out with this point's per-scale thresholds, the other
    optional keys (``threshold.rule``, ``threshold.calibration_scene``, ``noise.preset``)
    commented out with an example value.
    """
    lines = [
        "# rvsm fixed-point design point (SPEC section 5); see docs/fixed-point.md.",
        "# Check it with `rvsm config check FILE`.",
    ]
    section = None
    for f in FIELDS:
        if f.section != section:
            section = f.section
            lines += ["", f"# {SECTION_COMMENTS[section]}", f"[{section}]"]
        value = getattr(point, f.name)
        lines.append(f"# {f.key}: {f.comment()}")
        if value is None and f.name in _EXAMPLES:
            lines.append(f"# {tomli_w.dumps({f.key: _EXAMPLES[f.name]}).rstrip()}")
        elif value is None:
            example = ", ".join(repr(float(v)) for v in point.phis)
            lines.append(f"# {f.key} = [{example}]")
        else:
            lines.append(tomli_w.dumps({f.key: _toml_value(value)}).rstrip("\n"))
    return "\n".join(lines) + "\n"


def new_point_toml(point: DesignPoint) -> str:
    """:func:`design_point_toml` followed by the ``[rtl]`` table commented out (what
    ``rvsm config new`` writes; :func:`design_point_toml` alone stays the text that names
    a point in sweeps and stimulus files)."""
    return design_point_toml(point) + build_settings_toml()


def load_design_point(path: str | os.PathLike) -> DesignPoint:
    """Read and validate a design-point TOML file (errors name the file and the field);
    its ``[rtl]`` table is checked and left out (:func:`load_point_file` returns it)."""
    return load_point_file(path)[0]


def load_point_file(path: str | os.PathLike) -> tuple[DesignPoint, BuildSettings]:
    """Read and validate a design-point TOML file: the point and its build settings."""
    p = Path(path)
    return parse_point_file(read_utf8_text(p, "design point"), str(p))


def parse_design_point(text: str, source: str = "design point") -> DesignPoint:
    """Parse and validate design-point TOML text (its ``[rtl]`` table checked, left out)."""
    return parse_point_file(text, source)[0]


def parse_point_file(text: str, source: str = "design point"
                     ) -> tuple[DesignPoint, BuildSettings]:
    """Parse and validate design-point TOML text: the point and its ``[rtl]`` table."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RvsmError(f"{source}: not valid TOML: {exc}") from None
    build = BuildSettings.from_table(data.pop(BUILD_SECTION, None), source)
    return from_toml_dict(data, source, also=(BUILD_SECTION,)), build


def save_design_point(path: str | os.PathLike, point: DesignPoint) -> None:
    """Write ``point`` as commented TOML, atomically."""
    write_text_atomic(path, design_point_toml(point))
