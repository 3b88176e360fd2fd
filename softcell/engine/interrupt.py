"""The signals that stop a run: Ctrl-C (SIGINT) and SIGTERM, which batch schedulers send.

Within :func:`stop_signals` a stop signal raises :class:`KeyboardInterrupt` in the main
thread, so that every run saves its checkpoint, removes its temporary files and says where it
stopped; it records which signal came (:func:`received`; the command exits with 128 + its
number: 130 for SIGINT, 143 for SIGTERM). A signal arriving while a file is written
(:func:`deferred`: netCDF's library holds a lock there, and an exception raised inside it left
the cleanup waiting on that lock for good) is only recorded, and raised as the write ends.
A signal arriving while a stop is handled (in the ``except`` and ``finally`` blocks a
``KeyboardInterrupt`` passes through) or while a run cleans up (:func:`shielded`: temporary
files removed, a checkpoint saved, the folder's lock released) is only recorded, so a second
signal cannot break the cleanup; a third one ends the process at once (its lock goes with it;
the next run removes what it left). A simulation
also polls :func:`received` between chunks of samples: Python only prints a
``KeyboardInterrupt`` raised inside a finaliser (a progress bar's ``__del__``, an import
lock's callback), and the run must stop all the same; within :func:`stop_signals` that
print is left out (the stop is recorded, and said in one line), other unraisable errors are
printed as before.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

#: The signals handled as Ctrl-C.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)

#: The stop signal that ends the process at once, without cleaning up.
FORCE_AT = 3

_received: list[int] = []
_state: dict = {"pending": False, "deferring": 0, "hook": sys.unraisablehook}


def received() -> int | None:
    """The number of the stop signal received within :func:`stop_signals`, or None."""
    return _received[-1] if _received else None


def _quiet_stop(unraisable) -> None:
    """``sys.unraisablehook`` within :func:`stop_signals`: a ``KeyboardInterrupt`` that our
    handler raised inside a finaliser is not printed (the stop is recorded; the run stops at
    its next check); anything else goes to the hook that was there."""
    if issubclass(unraisable.exc_type, KeyboardInterrupt) and _received:
        return
    _state["hook"](unraisable)


def _handler(signum: int, frame: object) -> None:
    _received.append(signum)
    if len(_received) >= FORCE_AT:
        os.write(
            2,
            f"softcell: stopped at once ({len(_received)} stop signals): no checkpoint saved "
            "since the last one; rerun the same command to resume\n".encode(),
        )
        os._exit(128 + signum)
    if _state["deferring"]:
        _state["pending"] = True  # raised as the write in progress ends
        return
    if len(_received) > 1 or isinstance(sys.exc_info()[1], KeyboardInterrupt):
        # A stop in progress is not stopped again: neither in its except and finally blocks
        # nor after them, as the command unwinds (a second signal landed in the exit of
        # stop_signals itself: 1 of 100 pairs on a busy machine). The first is recorded and
        # polled, the third ends the process.
        return
    raise KeyboardInterrupt


@contextmanager
def deferred() -> Iterator[None]:
    """Within the block (a file being written), a stop signal is only recorded; the
    :class:`KeyboardInterrupt` it stands for is raised as the block ends without an error.
    Outside :func:`stop_signals` or the main thread it changes nothing."""
    with _holding(then_raise=True):
        yield


@contextmanager
def shielded() -> Iterator[None]:
    """Within the block (the cleanup of a run that is stopping already: its checkpoint
    saved, its temporary files removed, its lock released), a stop signal is only recorded
    (:func:`received`), never raised."""
    with _holding(then_raise=False):
        yield


@contextmanager
def _holding(then_raise: bool) -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _state["deferring"] += 1
    try:
        yield
    finally:
        _state["deferring"] -= 1
        if not _state["deferring"] and not then_raise:
            _state["pending"] = False
    if _state["pending"] and not _state["deferring"]:
        _state["pending"] = False
        raise KeyboardInterrupt


@contextmanager
def stop_signals() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`KeyboardInterrupt` (within
    :func:`deferred`, once, as it ends), every one is recorded (:func:`received`) and the
    third ends the process; the previous handlers and a clean record are restored on exit.
    Outside the main thread (where Python delivers no signal) it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.signal(number, _handler) for number in STOP_SIGNALS}
    _received.clear()
    _state.update(pending=False, deferring=0, hook=sys.unraisablehook)
    sys.unraisablehook = _quiet_stop
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        sys.unraisablehook = _state["hook"]
        _received.clear()
        _state.update(pending=False, deferring=0)


def exit_status(default: int = signal.SIGINT) -> int:
    """The exit status of a command stopped by a signal: 128 + its number (130 when none was
    recorded, as after a ``KeyboardInterrupt`` raised by hand)."""
    return 128 + (received() or default)
