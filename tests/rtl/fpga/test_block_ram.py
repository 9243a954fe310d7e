"""The block-RAM packing model against hand-worked counts, brute force and the RTL."""

from __future__ import annotations

import dataclasses

import pytest

from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.block_ram import (
    MemoryShape,
    ScaleState,
    StateLayout,
    pack,
    pack_state,
    state_memories,
)
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.devices import (
    DP16KD,
    SB_RAM40_4K,
    SB_SPRAM256KA,
    Aspect,
    get_budget,
)
from rvsm.rtl.fpga.ecp5_memory import dp16kd_count
from rvsm.rtl.stream.dimensions import StreamGeometry

ECP5 = get_budget("ecp5-85")


def _shared(model: str, bits: int, scales: int) -> StateLayout:
    return StateLayout(250, 400, (ScaleState(bits, 0),) * scales, adc_bits=7, radius=1)


def test_chip_notes_dog4_shared_thresholds_at_40_lanes_is_80_by_5() -> None:
    # chip-notes.md: 40 x 4 x 18 = 2880 bits = 80 x 36; 100000 / 40 = 2500 words = 5 x 512
    sp = pack_state(_shared("dog4", 18, 4), 40, ECP5, "packed")
    (acc,) = [row for row in sp.placed if row[0].name == "accumulators"]
    assert (acc[0].depth, acc[0].width) == (2500, 2880)
    assert acc[2] == 400 and "80 x 5 of 512x36 (pseudo-dual)" in acc[3]
    assert sp.bram == 400 > ECP5.bram


def test_chip_notes_dog2_a17_shared_thresholds_is_38_by_5() -> None:
    # 40 x 2 x 17 = 1360 bits = 37 x 36 + 28: 38 slices of 512x36 (a 28-bit slice in any
    # other aspect takes as many: 1Kx18 is 3 deep, twice), 5 deep
    sp = pack_state(_shared("dog2", 17, 2), 40, ECP5, "packed")
    assert sp.bram == 190 <= ECP5.bram
    (acc,) = [row for row in sp.placed if row[0].name == "accumulators"]
    assert acc[0].width == 1360


def test_default_point_per_pixel_thresholds_packed_is_779() -> None:
    # accumulators 2500 x 2880: 400; thresholds 2500 x 2720 = 75 x 36 + 20 bits:
    # 75 x 5 + a 1Kx18 slice 3 deep + a 8Kx2 slice 1 deep = 379
    lay = StateLayout.from_contract(default_design_point().contract())
    sp = pack_state(lay, 40, ECP5, "packed")
    assert [r[2] for r in sp.placed if r[1] == "bram"] == [400, 379]
    assert sp.bram == 779
    # the line buffer: 10 words of 2L x P x N = 6 x 40 x 7 bits, 16x4 distributed RAMs
    assert sp.lutram == 6 * 40 * 7 // 4 and sp.lutram_lut4 == 4 * sp.lutram


@pytest.mark.parametrize("model,size,lanes", [
    ("dog4", (64, 64), 1), ("dog4", (64, 64), 4), ("dog4", (64, 64), 8),
    ("dog2", (16, 400), 40), ("dog4", (250, 400), 40), ("dog1", (48, 40), 5),
])
def test_rtl_organisation_counts_the_rtls_own_block_rams(model, size, lanes) -> None:
    point = dataclasses.replace(default_design_point(), model=model).with_size(*size)
    c = point.contract()
    geo = StreamGeometry(c, lanes)
    # the RTL: per scale an accumulator and a threshold BankedMemory of geo.bank_sizes
    # banks, each an Ecp5BlockRam of dp16kd_count(word) DP16KD side by side
    rtl = c.num_scales * len(geo.bank_sizes) * (
        dp16kd_count(lanes * c.accumulator_bits) + dp16kd_count(lanes * c.threshold_bits))
    sp = pack_state(StateLayout.from_contract(c), lanes, ECP5, "rtl")
    assert sp.bram == rtl


def test_rtl_organisation_matches_the_measured_dp16kd_of_docs_fpga() -> None:
    # docs/fpga.md, best of 3 seeds at 64x64: P = 1 and 4 place 32 DP16KD, P = 8 64
    lay = StateLayout.from_contract(default_design_point().with_size(64, 64).contract())
    assert [pack_state(lay, p, ECP5, "rtl").bram for p in (1, 4, 8)] == [32, 32, 64]
    # packing 512-word banks in 512x36 halves P = 8
    assert pack_state(lay, 8, ECP5, "per-scale").bram == 32


@pytest.mark.parametrize("depth,width,expect", [
    (1024, 18, 1), (1024, 19, 2), (2048, 9, 1), (512, 72, 2), (25000, 18, 25),
    (4096, 13, 3),  # 2Kx9 (2 deep) + 4Kx4: fewer than any one aspect (4)
    (16384, 1, 1), (100, 1, 1), (0, 5, 0),
])
def test_pack_hand_worked(depth: int, width: int, expect: int) -> None:
    assert pack(MemoryShape("m", depth, width), DP16KD).primitives == expect


def _brute(depth: int, width: int, aspects: tuple[Aspect, ...]) -> int:
    """Every count of slices per aspect that covers ``width``: the fewest primitives."""
    def best(i: int, rest: int) -> float:
        if rest <= 0:
            return 0
        if i == len(aspects):
            return float("inf")
        a = aspects[i]
        return min(n * -(-depth // a.depth) + best(i + 1, rest - n * a.width)
                   for n in range(-(-rest // a.width) + 1))

    return int(best(0, width))


@pytest.mark.parametrize("depth", [1, 300, 512, 700, 1024, 1500, 2048, 3000, 5000, 9000])
def test_pack_is_optimal_against_brute_force(depth: int) -> None:
    for width in range(1, 41):
        got = pack(MemoryShape("m", depth, width), DP16KD).primitives
        assert got == _brute(depth, width, DP16KD.aspects), (depth, width)


def test_ports_replicas_and_single_port_words() -> None:
    # two reads a cycle: the pseudo-dual-only 512x36 needs a copy per read, a
    # true-dual 1Kx18 serves 2 reads when nothing is written
    two_reads = pack(MemoryShape("m", 512, 36, reads=2, writes=0), DP16KD)
    assert two_reads.primitives == 2 and two_reads.replicas == 1
    only_pdp = pack(MemoryShape("m", 512, 36, reads=2), DP16KD,
                    (Aspect(512, 36, "pseudo-dual"),))
    assert only_pdp.replicas == 2 and only_pdp.primitives == 2
    # three writes a cycle: no DP16KD aspect serves them
    assert pack(MemoryShape("m", 512, 36, reads=0, writes=3), DP16KD) is None
    # the UP5K SPRAM (16Kx16, one port): a read and a write per beat take words of two
    # beats, 8K x 32: two SPRAMs side by side
    sp = pack(MemoryShape("m", 16384, 16), SB_SPRAM256KA)
    assert sp.beats == 2 and sp.primitives == 2
    # iCE40 RAM4K: pseudo-dual 256x16 .. 2Kx2
    assert pack(MemoryShape("m", 256, 16), SB_RAM40_4K).primitives == 1
    assert pack(MemoryShape("m", 4096, 3), SB_RAM40_4K).primitives == 4  # 2Kx2, 2 deep x 2 wide


def test_layout_bits_equal_the_state_memory_and_pitch_divides_them() -> None:
    c = default_design_point().contract()
    st = state_memory(c)
    lay = StateLayout.from_contract(c)
    assert lay.total_bits == st.total
    assert (lay.accumulator_bits, lay.threshold_bits, lay.line_buffer_bits) == (
        st.accumulators, st.thresholds, st.line_buffers)
    assert StateLayout.from_contract(c, shared_thresholds=True).threshold_bits == 0
    coarse = StateLayout.from_contract(c, True, pitches=(1, 2, 4, 8))
    kept = sum(lay.kept(p) for p in (1, 2, 4, 8))
    assert coarse.accumulator_bits == kept * c.accumulator_bits
    assert lay.kept(8) == 32 * 50
    with pytest.raises(RvsmError, match="pitches"):
        StateLayout.from_contract(c, pitches=(1, 2))


def test_memories_of_each_organisation_hold_the_layouts_bits() -> None:
    lay = StateLayout.from_contract(default_design_point().contract(), False, (1, 1, 2, 2))
    for org in ("rtl", "per-scale", "packed"):
        mems = state_memories(lay, 40, org)
        state = sum(m.bits for m in mems if m.name != "line buffer")
        assert state == lay.accumulator_bits + lay.threshold_bits, org
        (line,) = [m for m in mems if m.name == "line buffer"]
        assert line.bits == lay.line_buffer_bits
    packed = [m.name for m in state_memories(lay, 40, "packed")]
    assert packed == ["accumulators", "thresholds", "accumulators (pitch 2)",
                      "thresholds (pitch 2)", "line buffer"]
    assert all(m.depth <= 1024 for m in state_memories(lay, 40, "rtl"))
    with pytest.raises(RvsmError, match="rtl, per-scale, packed"):
        state_memories(lay, 40, "sideways")


def test_devices_without_distributed_ram_keep_the_line_buffer_in_block_ram() -> None:
    lay = StateLayout(16, 40, (ScaleState(10, 0),), adc_bits=7, radius=2)
    ice = pack_state(lay, 4, get_budget("ice40-hx8k"))
    assert [w for m, w, _, _ in ice.placed if m.name == "line buffer"] == ["bram"]
    assert ice.lutram == 0
    ecp5 = pack_state(lay, 4, ECP5)
    assert [w for m, w, _, _ in ecp5.placed if m.name == "line buffer"] == ["lutram"]
    # the UP5K puts the state in its SPRAM while they have room
    up5k = pack_state(StateLayout(128, 128, (ScaleState(16, 0),), 7, 0), 1,
                      get_budget("ice40-up5k"))
    assert up5k.extra == 2 and up5k.bram == 0


@pytest.mark.parametrize(("kw", "mbit", "blocks"), [
    ({"model": "dog4"}, (14.0168, 7.2168), (779, 400)),
    ({"model": "dog2", "shift": 1, "accumulator_bits": 17}, (6.6056, 3.4056), (369, 190)),
])
def test_threshold_storage_of_the_point_reaches_the_layout(kw, mbit, blocks) -> None:
    """threshold.storage = "shared" -> the contract's shared_thresholds -> no threshold
    memory in the layout, the state memory and the geometry (chip-notes.md figures)."""
    got_bits, got_blocks = [], []
    for storage in ("per-pixel", "shared"):
        c = DesignPoint(threshold_storage=storage, **kw).contract()
        layout = StateLayout.from_contract(c)
        assert layout.total_bits == state_memory(c).total
        assert (layout.threshold_bits == 0) == (storage == "shared")
        assert (StreamGeometry(c, 40).state_bits["thresholds"] == 0) == (storage == "shared")
        got_bits.append(round(layout.total_bits / 1e6, 4))
        got_blocks.append(pack_state(layout, 40, ECP5, "packed").bram)
    assert tuple(got_bits) == mbit and tuple(got_blocks) == blocks
