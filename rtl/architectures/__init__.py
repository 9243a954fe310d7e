"""The registry of RTL architectures (:mod:`.registry`): above the architecture packages it
lists (``rtl/parallel``, ``rtl/stream``, ``rtl/ip``), which build on the shared modules at
the top of ``rtl/`` (``capabilities.py``, ``ports.py``...), so no folder imports back."""
