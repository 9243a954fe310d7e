import numpy as np
import pytest

from rvsm.model.spikes.packing import count_spikes, pack_spikes, unpack_spikes


@pytest.mark.parametrize("width", [1, 3, 4, 5, 8, 11])
def test_two_bit_packing_round_trip(width):
    a = np.random.default_rng(0).integers(-1, 2, (3, 2, 4, width)).astype(np.int8)
    packed = pack_spikes(a)
    assert packed.dtype == np.uint8 and packed.shape[-1] == (width + 3) // 4
    np.testing.assert_array_equal(unpack_spikes(packed, width), a)
    assert pack_spikes(np.array([[1, -1, 0, 1]], dtype=np.int8))[0, 0] == 0b01001101
    nz, neg = count_spikes(a)
    np.testing.assert_array_equal(nz, np.count_nonzero(a, axis=(0, 2, 3)))
    assert neg == int((a < 0).sum())
