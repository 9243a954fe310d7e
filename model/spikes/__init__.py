"""Spike I/O, one module per format or concept: ``.npz`` files (:mod:`.npz`), the camera's
``.dat`` (:mod:`.dat`), chunked HDF5 (:mod:`.h5`), two-bit packing (:mod:`.packing`),
array checks (:mod:`.arrays`), the sinks a chunked run writes to (:mod:`.sinks`), the
reader interface (:mod:`.source`) and the by-suffix entry points ``open_spike_file`` /
``write_spikes`` (:mod:`.files`). Every file a sensor writes, the event sensor's HDF5
event lists included, is opened by :func:`rvsm.model.sensors.files.open_spikes`."""
