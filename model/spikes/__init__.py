"""Spike I/O, one module per format or concept: ``.npz`` files (:mod:`.npz`), the camera's
``.dat`` (:mod:`.dat`), chunked HDF5 (:mod:`.h5`), two-bit packing (:mod:`.packing`),
array checks (:mod:`.arrays`), the sinks a chunked run writes to (:mod:`.sinks`), the
reader interface (:mod:`.source`) and the by-suffix entry points ``open_spikes`` /
``write_spikes`` (:mod:`.files`)."""
