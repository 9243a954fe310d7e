"""Spike files: ``.npz`` and the camera's ``.dat`` (:mod:`.npz`), chunked HDF5 and the
reader of every format (:mod:`.h5`), two-bit packing (:mod:`.packing`)."""
