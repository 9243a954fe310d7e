"""Infrastructure shared by every layer, not model: the one error type, atomic writes,
external tools in their own process group, progress bars, software versions, memory and
input guards (``.npy`` headers, UTF-8 text files)."""
