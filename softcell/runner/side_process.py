"""A function run in a process of its own, beside the caller: one core each.

:class:`Alongside` starts ``fn(*args, **kwargs)`` in a spawned process (no state inherited
from a parent that has started threads or compiled code) and hands back its result or
raises its error in the caller. Leaving the ``with`` block early (an error or Ctrl-C in
the caller) terminates the process, so nothing runs on unseen; a process that dies without a
result (killed, out of memory) is reported with its exit code.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Callable
from typing import Any

from softcell.errors import SoftcellError


def _run(send: Any, fn: Callable[..., Any], args: tuple, kwargs: dict[str, Any]) -> None:
    start = time.perf_counter()
    try:
        value = fn(*args, **kwargs)
    except BaseException as error:  # noqa: BLE001  (handed to the caller, which raises it)
        send.send((False, error, time.perf_counter() - start))
    else:
        send.send((True, value, time.perf_counter() - start))
    finally:
        send.close()


class Alongside:
    """``fn(*args, **kwargs)`` in a spawned process; :meth:`result` waits for it.

    ``fn``, its arguments and its result must pickle. Use as a context manager: leaving the
    block terminates the process if it still runs. ``seconds`` is the process' own wall
    time of ``fn`` (s), known once :meth:`result` has returned.
    """

    def __init__(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> None:
        context = multiprocessing.get_context("spawn")
        self._receive, send = context.Pipe(duplex=False)
        self.name = getattr(fn, "__name__", repr(fn))
        self._process = context.Process(
            target=_run, args=(send, fn, args, kwargs), name=f"softcell-{self.name}"
        )
        self._process.start()
        send.close()  # the child holds the only sending end: its death ends the pipe
        self.seconds: float | None = None

    def result(self) -> Any:
        """Wait for ``fn`` and return its value (or raise its error)."""
        try:
            ok, value, self.seconds = self._receive.recv()
        except EOFError:
            self._process.join()
            raise SoftcellError(
                f"{self.name}, run in a process of its own, ended without a result (exit "
                f"code {self._process.exitcode})"
            ) from None
        self._process.join()
        if not ok:
            raise value
        return value

    def __enter__(self) -> Alongside:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._process.is_alive():
            self._process.terminate()
        self._process.join()
        self._receive.close()
