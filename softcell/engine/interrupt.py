"""The signals that stop a run: Ctrl-C (SIGINT) and SIGTERM, which batch schedulers send.

:func:`stop_signals` makes both raise :class:`KeyboardInterrupt` in the main thread, so that
every run saves its checkpoint, removes its temporary files and says where it stopped, and
records which signal came (:func:`received`; the command exits with 128 + its number: 130
for SIGINT, 143 for SIGTERM). A simulation also polls :func:`received` between chunks of
samples: Python only prints a ``KeyboardInterrupt`` raised inside a finaliser, and the run
must stop all the same.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

#: The signals handled as Ctrl-C.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)

_received: list[int] = []


def received() -> int | None:
    """The number of the stop signal received within :func:`stop_signals`, or None."""
    return _received[-1] if _received else None


def _handler(signum: int, frame: object) -> None:
    _received.append(signum)
    raise KeyboardInterrupt


@contextmanager
def stop_signals() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`KeyboardInterrupt` and are
    recorded (:func:`received`); the previous handlers and a clean record are restored on
    exit. Outside the main thread (where Python delivers no signal) it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.signal(number, _handler) for number in STOP_SIGNALS}
    _received.clear()
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        _received.clear()


def exit_status(default: int = signal.SIGINT) -> int:
    """The exit status of a command stopped by a signal: 128 + its number (130 when none was
    recorded, as after a ``KeyboardInterrupt`` raised by hand)."""
    return 128 + (received() or default)
