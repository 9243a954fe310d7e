"""Interfaces of the streaming array: its input and output streams and threshold bus.

:func:`code_beat_signature` (``P`` ADC codes per beat, valid/ready),
:func:`spike_beat_signature` (position and ``S*P`` spikes per beat, no back-pressure)
and :func:`threshold_write_signature` (the shared
:class:`~rvsm.rtl.interfaces.ThresholdWriteSignature`, one memory word per write).
"""

from __future__ import annotations

from amaranth.hdl import unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import Out

from rvsm.rtl.interfaces import ThresholdWriteSignature

__all__ = [
    "code_beat_signature",
    "field_bits",
    "spike_beat_layout",
    "spike_beat_signature",
    "threshold_word_bits",
    "threshold_write_signature",
]


def field_bits(max_value: int) -> int:
    """Bits of an unsigned field holding ``0 .. max_value`` (at least 1)."""
    return max(1, int(max_value).bit_length())


def code_beat_signature(adc_bits: int, lanes: int) -> stream.Signature:
    """Input stream: ``payload`` = ``lanes`` unsigned ADC codes, ``valid``, ``ready``."""
    return stream.Signature(data.ArrayLayout(unsigned(adc_bits), lanes))


def spike_beat_layout(num_scales: int, lanes: int, height: int,
                      groups: int) -> data.StructLayout:
    """Output payload: ``row``, ``group``, ``last``, ``pos`` and ``neg`` (``S*P`` bits)."""
    return data.StructLayout({
        "row": unsigned(field_bits(height - 1)),
        "group": unsigned(field_bits(groups - 1)),
        "last": unsigned(1),
        "pos": unsigned(num_scales * lanes),
        "neg": unsigned(num_scales * lanes),
    })


def spike_beat_signature(num_scales: int, lanes: int, height: int,
                         groups: int) -> wiring.Signature:
    """Output stream of :func:`spike_beat_layout` beats: ``payload`` and ``valid``, no
    ``ready`` (a sensor cannot be stopped: there is no back-pressure)."""
    return wiring.Signature({
        "payload": Out(spike_beat_layout(num_scales, lanes, height, groups)),
        "valid": Out(1),
    })


def threshold_word_bits(words: int) -> int:
    """Bits of the word part (``y*G + g``) of a threshold write address."""
    return field_bits(words - 1)


def top_threshold_word(threshold_bits: int, lanes: int) -> int:
    """A threshold word with every lane at the top rail ``2**(W-1)-1``: what the
    threshold memories hold at configuration (no spike until thresholds are loaded)."""
    top = (1 << threshold_bits) - 1
    return sum(top << (i * threshold_bits) for i in range(lanes))


def threshold_write_signature(num_scales: int, words: int, lanes: int,
                              threshold_bits: int, shared: bool = False
                              ) -> ThresholdWriteSignature:
    """The shared threshold-write bus with one memory word (P thresholds) per write:
    ``data`` lane ``i`` at ``[i*(W-1) +: W-1]``, ``addr = (s << word_bits) | (y*G + g)``
    (:func:`threshold_word_bits`). ``shared`` (one threshold register per scale,
    ``threshold.storage = "shared"``): ``addr = s`` and ``data`` one threshold."""
    if shared:
        return ThresholdWriteSignature(threshold_bits, field_bits(num_scales - 1))
    return ThresholdWriteSignature(lanes * threshold_bits,
                                   field_bits(num_scales - 1) + threshold_word_bits(words))

