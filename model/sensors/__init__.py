"""The sensors, registered: each a value composing what the packages below do for it.

The top of ``rvsm.model`` on the sensor axis (``docs/architecture.md``): a
:class:`~.capabilities.Sensor` (:mod:`.capabilities`) carries its declarative kind
(:mod:`rvsm.model.kinds.sensor_kind`: name, output rule), its float twin, the float model
a design point approximates, its decoder and the kinds of file it writes; the registry
(:mod:`.registry`) holds the spike camera (:mod:`.spike_camera`) and the event sensor
(:mod:`.event_sensor`), looked up by name once where a name is read. What combines
several sensors' packages lives here too: every file format behind one reader
(:mod:`.files`) and the quantisation cost of a design point (:mod:`.cost`).
"""
