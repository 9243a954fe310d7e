"""Float and fixed-point models of the RVSM spike-camera pixel array.

Submodules, one concept each:

- :mod:`kernels` -- normalised DoG / Gauss receptive fields and the scale ladders.
- :mod:`scene` -- a scene (frames + ``steps_per_frame``) and its per-step brightness.
- :mod:`scene_library` / :mod:`scene_io` -- built-in synthetic scenes and file loaders.
- :mod:`noise` -- dark current and fixed-pattern threshold noise (SPEC section 3).
- :mod:`samplers` -- the float FSM / RVSM samplers (SPEC section 2).
- :mod:`spike_files` -- ``.npz`` spike files and the spike camera's ``.dat`` layout.
- :mod:`reconstruction`, :mod:`metrics` -- TFI/TFP, the RVSM adjoint, PSNR/SSIM, robustness.
- :mod:`inverse` -- the least-squares inverse of the RVSM filter bank (CG).
- :mod:`thresholds` -- per-scale threshold rules: equal, equal response time.
- :mod:`noise_presets` / :mod:`noise_calibration` -- named noise regimes and the
  calibration of the ``paper`` preset on FSM.
- :mod:`fixed` -- the bit-accurate fixed-point twin (SPEC section 5).
"""

import os as _os

# Numba's fused kernels and the counter-based noise streams must round the same whether a
# loop is vectorised or not: no Intel SVML vector maths (set before numba is imported).
_os.environ.setdefault("NUMBA_DISABLE_INTEL_SVML", "1")
