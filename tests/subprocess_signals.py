"""Children of the tests that must take Ctrl-C."""

import signal


def interruptible() -> None:
    """In the child, before it starts: SIGINT handled by default.

    A runner started in the background (``cmd &`` in a script) ignores SIGINT, and an ignored
    signal stays ignored across exec: Python would then never raise KeyboardInterrupt.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)
