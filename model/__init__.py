"""Float and fixed-point models of the RVSM spike-camera pixel array (``rvsm.model``).

Sub-packages, one concern each (the layering is ``sim -> rtl -> model``; nothing here
imports ``rtl`` or ``sim``):

- :mod:`.scene` -- a scene (frames + ``steps_per_frame``), its per-step brightness, the
  built-in synthetic scenes and the file loaders.
- :mod:`.kernels` -- normalised DoG / Gauss receptive fields, the scale ladders, the orbit
  order of the receptive sums.
- :mod:`.noise` -- dark current and fixed-pattern threshold noise (SPEC section 3), its
  counter-based streams and the named presets.
- :mod:`.sampling` -- the float twin (SPEC section 2): configuration and results, the
  numpy and fused numba engines, one chunked run pipeline (``sample``,
  ``stream_float``), threshold rules and the literal SPEC oracle.
- :mod:`.fixed` -- the bit-accurate fixed-point twin (SPEC section 5) of either sensor:
  design points and their rules per sensor kind, the
  :class:`~.fixed.contract.ArrayContract`, the numpy and fused engines and one run
  pipeline (``simulate_fixed``, ``stream_fixed``), stimulus and profile.
- :mod:`.events` -- the event sensor, RVSM-DVS (SPEC section 7): its float twin, its
  decoder and HDF5 event lists.
- :mod:`.spikes` -- spike I/O: ``.npz``, the camera's ``.dat``, chunked HDF5, two-bit
  packing, the sinks a chunked run writes to and one by-suffix reader
  (``open_spike_file``).
- :mod:`.decode` -- reconstruction (TFI/TFP, the RVSM adjoint, the least-squares inverse),
  metrics (PSNR/SSIM) and evaluation, whole-array or streamed.
- :mod:`.kinds` -- the sensor kind as a declarative value (``SensorKind``, its output
  rule), importing nothing of the other sub-packages, so all may take it.
- :mod:`.sensors` -- the top: the registered sensors (spike camera, event sensor)
  composing the sub-packages above (float twin, decoder, file kinds), every file format
  behind one reader (``open_spikes``) and the quantisation cost of a design point.
- :mod:`.infra` -- what the models run on: errors and exit statuses, atomic writes,
  external tools, progress bars, versions, memory checks, text and ``.npy`` guards.
"""

import os as _os

# Numba's fused kernels and the counter-based noise streams must round the same whether a
# loop is vectorised or not: no Intel SVML vector maths (set before numba is imported).
_os.environ.setdefault("NUMBA_DISABLE_INTEL_SVML", "1")

# 512-bit vectors where the host has AVX-512 (same results, faster; RVSM_SIMD=256 opts out).
from rvsm.model.infra.simd import prefer_512_bit_vectors as _prefer_512_bit_vectors  # noqa: E402

_prefer_512_bit_vectors()
