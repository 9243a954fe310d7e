"""Link status and control: the signatures, and the register block for the AXI IP.

:class:`LinkStatusSignature` is what :class:`~rvsm.rtl.board.receiver.LinkReceiver`
reports in the core clock domain (``locked``, ``aligned``, per-pair error counters,
lock losses, FIFO overflow); :class:`LinkControlSignature` what it takes (``train``: a
training request held while high, ``counters_reset``: a one-cycle pulse zeroing the
counters). :func:`link_registers` declares them as registers in the style of
:mod:`rvsm.rtl.ip.register_map` (:class:`~rvsm.rtl.ip.register_map.Register` of
:class:`~rvsm.rtl.ip.register_map.Field`), the IP's ``extra_registers``
(:class:`~rvsm.rtl.board.ip_front_end.IpBoardFrontEnd`);
:func:`register_values` gives each register's live value from the status signals.
"""

from __future__ import annotations

from amaranth.hdl import Cat, Const, Value
from amaranth.lib import data, wiring
from amaranth.lib.wiring import Out

from rvsm.rtl.ip.register_map import EXTRA_WINDOW, Field, Register

__all__ = ["COUNTER_BITS", "LINK_BASE", "LinkControlSignature", "LinkStatusSignature",
           "link_registers", "link_registers_markdown", "register_values"]

#: Bits of each per-pair error counter (saturating) and of the lock-loss counter.
COUNTER_BITS = 8
#: Byte offset of the link block: the start of the IP's window for a wrapper's registers
#: (:data:`~rvsm.rtl.ip.register_map.EXTRA_WINDOW`, 0x080-0x0FC).
LINK_BASE = EXTRA_WINDOW.start


class LinkStatusSignature(wiring.Signature):
    """Receiver status (core domain), all driven by the receiver: ``locked`` (the
    forwarded clock runs and the link is trained and deskewed), ``aligned`` (every pair
    word-aligned), ``lane_errors`` (per pair: words breaking the protocol, saturating;
    the framing lane also counts parity errors), ``lock_losses`` (falls of ``locked``,
    saturating), ``overflow`` (a beat was lost: the core did not keep up; sticky until
    ``counters_reset``)."""

    def __init__(self, pairs: int):
        self.pairs = pairs
        super().__init__({
            "locked": Out(1), "aligned": Out(1),
            "lane_errors": Out(data.ArrayLayout(COUNTER_BITS, pairs)),
            "lock_losses": Out(COUNTER_BITS), "overflow": Out(1),
        })


class LinkControlSignature(wiring.Signature):
    """Receiver control (core domain), driven by the host: ``train`` (request training:
    drop alignment and search again while high; the board's ``train_request`` pin tells
    the sensor) and ``counters_reset`` (a one-cycle pulse)."""

    def __init__(self) -> None:
        super().__init__({"train": Out(1), "counters_reset": Out(1)})


def link_registers(pairs: int, base: int = LINK_BASE) -> tuple[Register, ...]:
    """The link's registers at byte offsets from ``base``: LINK_STATUS, LINK_CONTROL,
    LINK_LOSSES and ``ceil(pairs / 4)`` LINK_ERRORS<k> (four 8-bit counters each, pair
    ``4k + j`` at bits ``[8j +: 8]``; the last pair is the framing lane)."""
    regs = [
        Register("LINK_STATUS", base, (
            Field("locked", 0, 1, "RO", 0, "the forwarded clock runs and every pair is "
                  "aligned and deskewed", live=True),
            Field("aligned", 1, 1, "RO", 0, "every pair is word-aligned on the training "
                  "word", live=True),
            Field("train_request", 2, 1, "RO", 1, "training is requested from the sensor "
                  "(not locked, or LINK_CONTROL.train)", live=True),
            Field("overflow", 3, 1, "RO", 0, "a received beat was lost (the core did not "
                  "keep up); cleared by LINK_CONTROL.counters_reset", live=True)),
            "receive link status"),
        Register("LINK_CONTROL", base + 4, (
            Field("train", 0, 1, "RW", 0, "request training: alignment is dropped and "
                  "searched again while 1"),
            Field("counters_reset", 1, 1, "WO", 0, "zero the link's error and loss "
                  "counters and overflow")),
            "receive link control"),
        Register("LINK_LOSSES", base + 8, (
            Field("count", 0, COUNTER_BITS, "RO", 0, "falls of locked (saturating)",
                  live=True),), "lock losses"),
    ]
    for k in range(-(-pairs // 4)):
        fields = tuple(Field(f"pair{4 * k + j}", 8 * j, COUNTER_BITS, "RO", 0,
                             "framing lane: framing and parity errors" if 4 * k + j == pairs - 1
                             else f"pair {4 * k + j}: words breaking the protocol",
                             live=True)
                       for j in range(min(4, pairs - 4 * k)))
        regs.append(Register(f"LINK_ERRORS{k}", base + 12 + 4 * k, fields,
                             f"error counters of pairs {4 * k}..{4 * k + len(fields) - 1} "
                             "(saturating)"))
    return tuple(regs)


def register_values(status: wiring.PureInterface, train: Value, train_request: Value
                    ) -> dict[str, Value]:
    """Each read-only register's value from a :class:`LinkStatusSignature` interface,
    the ``train`` bit and the ``train_request`` pin (LINK_CONTROL reads ``train``)."""
    pairs = len(status.lane_errors)
    values = {
        "LINK_STATUS": Cat(status.locked, status.aligned, train_request, status.overflow),
        "LINK_CONTROL": Cat(train, Const(0, 1)),
        "LINK_LOSSES": status.lock_losses,
    }
    for k in range(-(-pairs // 4)):
        values[f"LINK_ERRORS{k}"] = Cat(status.lane_errors[j]
                                        for j in range(4 * k, min(4 * k + 4, pairs)))
    return values


def link_registers_markdown(registers: tuple[Register, ...]) -> str:
    """The link registers as a Markdown table (``docs/board.md``): offset, name, access,
    reset value and each field's bits and access."""
    lines = ["| offset | register | access | reset | fields |", "|---|---|---|---|---|"]
    for r in registers:
        fields = ", ".join(f"`{f.name}` [{f.lsb + f.width - 1}:{f.lsb}] {f.access}"
                           if f.width > 1 else f"`{f.name}` [{f.lsb}] {f.access}"
                           for f in r.fields)
        lines.append(f"| 0x{r.offset:03X} | `{r.name}` | {r.access} | 0x{r.reset:08X} | "
                     f"{fields}: {r.desc} |")
    return "\n".join(lines) + "\n"
