"""Formal harnesses: named properties around an RTL block, for ``rvsm formal``.

A harness (:class:`FormalHarness`) is an ``Elaboratable`` that instantiates a block (the
streaming array, the parallel array, a miter of two), drives its inputs from
``AnySeq``/``AnyConst`` (``amaranth.asserts``) under ``Assume`` s, and states what must
hold with ``Assert`` and what must be reachable with ``Cover``. Every statement is made
through :meth:`FormalHarness.check` so that it has a name, a description and the source
line sby reports (``file:line``), which :func:`property_at` maps back to the name.

Properties never reach a user's Verilog: harnesses are only elaborated for the
``"formal"`` platform (``rtlil.convert(..., platform="formal")``). A harness must drive or
constrain the ``sync`` domain's reset itself (sby runs it with ``multiclock off``: every
step is one clock edge; an unconstrained ``rst`` is a free input).

Architectures list their harness factories in :attr:`Architecture.formal`:
``factory(contract, mutation=None, **options) -> FormalHarness``.
"""

from __future__ import annotations

import inspect
import os
from dataclasses import dataclass

from amaranth.hdl import Assert, Assume, Cover, Elaboratable, Module, Value

__all__ = ["KINDS", "ElaborateAfter", "FormalHarness", "Property", "property_at"]

#: Statement kinds: checked (``assert``), reachable (``cover``), constraint (``assume``).
KINDS = ("assert", "cover", "assume")


class ElaborateAfter(Elaboratable):
    """Calls ``build(platform)`` when elaborated: properties that observe a block's
    internals (cells, probes), added as a submodule after the block so that the block
    is elaborated first."""

    def __init__(self, build) -> None:
        self.build = build

    def elaborate(self, platform: object) -> Module:
        return self.build(platform)


@dataclass(frozen=True)
class Property:
    """One named statement of a harness: ``name`` (``"handshake.no_loss"``), ``kind``
    (:data:`KINDS`), ``description`` (one line) and ``src`` (``"path/file.py:123"``, the
    line sby names when it fails)."""

    name: str
    kind: str
    description: str
    src: str


class FormalHarness(Elaboratable):
    """Base class of harnesses. Members:

    * ``properties``: the :class:`Property` s stated so far (filled during
      ``elaborate``; :meth:`statements` elaborates once to list them);
    * ``depth``: the bounded depth (clock cycles) the checks need (for the stream array:
      two frames plus the pipeline lag), used when ``--depth`` is not given;
    * ``provable``: whether k-induction is expected to close (small state), else BMC;
    * :meth:`smtbmc_options`: the options given to sby's ``smtbmc`` engine in a mode;
    * ``power_up_memories``: submodules (yosys patterns below the top, e.g.
      ``"dut.acc_s*"``) whose memories start with arbitrary contents, as a RAM does at
      power-up: their initial values are dropped before the solver sees the model.
    """

    depth: int = 20
    provable: bool = False
    #: Properties decided exactly in Python before the solver runs
    #: (:meth:`offline_failures`), e.g. the stream's ``sums.linear_forms``.
    offline_properties: tuple[str, ...] = ()
    power_up_memories: tuple[str, ...] = ()

    def __init__(self) -> None:
        self.properties: list[Property] = []

    def smtbmc_options(self, mode: str) -> tuple[str, ...]:
        """Options for sby's ``smtbmc`` engine in ``mode`` (``prove``, ``bmc``,
        ``cover``), e.g. ``("--syn",)`` (yosys synthesises the model before the solver
        sees it; equivalence-preserving). None by default; a harness overrides this with
        what measured fastest for it (``docs/formal.md``, "Times")."""
        return ()

    def check(self, m: Module, name: str, test: Value, description: str,
              kind: str = "assert", src_loc_at: int = 0) -> None:
        """Add ``test`` to ``m`` as a named ``Assert`` / ``Cover`` / ``Assume``
        (comb domain: it holds in every cycle where it is evaluated); its source line is
        the caller's (``src_loc_at`` frames further out for a wrapper)."""
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
        frame = inspect.stack()[1 + src_loc_at]
        src = f"{os.path.abspath(frame.filename)}:{frame.lineno}"
        statement = {"assert": Assert, "cover": Cover, "assume": Assume}[kind]
        m.d.comb += statement(test, name, src_loc_at=1 + src_loc_at)
        if not any(p.name == name and p.kind == kind for p in self.properties):
            self.properties.append(Property(name, kind, description, src))

    def offline_failures(self) -> list[tuple[str, str]]:
        """``(property, message)`` for each failure of :attr:`offline_properties`."""
        return []

    def statements(self) -> list[Property]:
        """Elaborate once (platform ``"formal"``) and list the properties."""
        from amaranth.hdl import Fragment

        self.properties = []
        Fragment.get(self, "formal")
        found, self.properties = list(self.properties), []
        return found


def property_at(properties: list[Property], location: str) -> Property | None:
    """The property whose ``src`` ends like sby's ``location`` (``file:line``, possibly
    with a column range ``file:12.3-12.40``), or None."""
    path, _, rest = location.rpartition(":")
    line = rest.split(".")[0]
    for prop in properties:
        p_path, _, p_line = prop.src.rpartition(":")
        if p_line == line and (p_path.endswith(path) or path.endswith(p_path)
                               or os.path.basename(p_path) == os.path.basename(path)):
            return prop
    return None
