"""The one exception type users see: a message that says what is wrong and how to fix it."""


class RvsmError(Exception):
    """A user-facing error (bad input, bad configuration, missing tool).

    The CLI prints ``rvsm: error: <message>`` on one line and exits non-zero; the message
    must name what is wrong and, where possible, how to fix it.
    """


class ToolError(RvsmError):
    """An external tool (synthesis, place-and-route, simulator) failed or is missing.

    The CLI prints it like :class:`RvsmError` but exits with status 3 (tool/environment
    failure) instead of 2 (bad input).
    """
