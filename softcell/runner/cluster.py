"""Running realizations on a dask.distributed cluster, one task each, and stopping them.

A local cluster of single-threaded worker processes, or the cluster whose scheduler listens at
an address (whose workers must see the output folder, e.g. on a shared file system). The
longest realizations start first; Ctrl-C asks the running ones to checkpoint and stop.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from softcell.engine import sampling_plan
from softcell.errors import Interrupted, SoftcellError
from softcell.runner.tasks import STOP_FILE, Task, checkpoint_path, read_checkpoint, run_task
from softcell.settings import CHECKPOINT_EVERY

#: Wall seconds a cluster's realizations get to checkpoint and stop after Ctrl-C.
STOP_GRACE = 30.0


@contextmanager
def cluster_client(workers: int, scheduler: str | None = None) -> Iterator[Any]:
    """A dask.distributed Client, as a context manager: of the scheduler at ``scheduler``, or
    of a new local cluster of ``workers`` single-threaded processes, closed on exit."""
    import logging

    from distributed import Client

    if scheduler is not None:
        check_scheduler(scheduler)
        try:
            client = Client(scheduler, timeout="30s")
        except (OSError, ValueError) as exc:  # ValueError: an inproc address that is not
            raise SoftcellError(
                f"cannot reach the dask scheduler at {scheduler!r}: {exc}"
            ) from None
        with client:
            yield client
        return
    logging.getLogger("distributed").setLevel(logging.ERROR)
    with _environment_restored():
        yield from _local_client(workers)


def _local_client(workers: int) -> Iterator[Any]:
    import logging

    from distributed import Client, LocalCluster

    # Workers log at ERROR only (a task cancelled by Ctrl-C is no warning to the user), and
    # ignore SIGINT, which a terminal sends the whole process group: this process handles
    # Ctrl-C, cancels the tasks and closes the cluster in order.
    with _sigint_ignored_by_children():
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            # The scheduler's HTTP server still listens (8787 by default, with a warning
            # for every second cluster on the machine): on a free loopback port instead.
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            silence_logs=logging.ERROR,
        )
    with cluster, Client(cluster) as client:
        yield client


@contextmanager
def _environment_restored() -> Iterator[None]:
    """Within the block, os.environ may change; on exit it is as before. A local cluster
    leaves its workers' settings in this process' environment (MALLOC_TRIM_THRESHOLD_,
    OMP_NUM_THREADS, PYTHONHASHSEED, ...), where every process started later would inherit
    them: with MALLOC_TRIM_THRESHOLD_ the video pipeline runs 1.3x slower."""
    before = dict(os.environ)
    try:
        yield
    finally:
        os.environ.clear()
        os.environ.update(before)


@contextmanager
def _sigint_ignored_by_children() -> Iterator[None]:
    """Within the block, SIGINT is ignored, so processes started here inherit that (an
    ignored signal stays ignored across fork and exec); restored on exit."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def run_on_cluster(
    tasks: list[Task],
    client,
    progress: Callable[[float], None] | None = None,
    checkpoint_every: float = CHECKPOINT_EVERY,
) -> list[str]:
    """Run ``tasks`` on a dask.distributed ``client``, one task per realization; each writes
    its own file atomically. ``progress`` is called with a task's simulated seconds when it
    ends. The longest tasks start first. The first failure cancels what has not started and
    is raised (finished files stay).
    """
    from distributed import as_completed

    # Longest first (priority = simulated seconds): a long realization submitted last would
    # run alone on one worker at the end while the others idle.
    futures = {
        client.submit(
            run_task,
            task,
            None,
            checkpoint_every,
            True,
            pure=False,
            priority=int(math.ceil(task.duration)),
        ): task
        for task in tasks
    }
    paths = []
    try:
        for future in as_completed(futures):
            paths.append(future.result())
            if progress:
                progress(futures[future].duration)
    except KeyboardInterrupt:
        raise Interrupted(_stop(client, futures)) from None
    except BaseException:
        client.cancel(list(futures))
        raise
    return paths


def _stop(client, futures: dict[Any, Task]) -> str:
    """After Ctrl-C: ask the running realizations to checkpoint and stop (through
    :data:`STOP_FILE`), wait for them (:data:`STOP_GRACE`, or a second Ctrl-C), cancel the rest,
    and say where the run stood."""
    from distributed import wait

    stop_files = {Path(t.path).parent / STOP_FILE for t in futures.values()}
    try:
        for stop_file in stop_files:
            stop_file.touch()
        wait(list(futures), timeout=STOP_GRACE)
    except (KeyboardInterrupt, TimeoutError, OSError):
        pass
    finally:
        client.cancel(list(futures))
        for stop_file in stop_files:
            stop_file.unlink(missing_ok=True)
    # What is finished is what is on disk (a cancelled future no longer says it finished).
    done = [t for t in futures.values() if Path(t.path).exists()]
    unfinished = [t for t in futures.values() if t not in done]
    return _where(unfinished, len(done), len(futures))


def _where(unfinished: list[Task], finished: int, total: int) -> str:
    """Where an interrupted cluster run stood, from the checkpoints of its unfinished tasks."""
    saved = []
    for task in unfinished:
        checkpoint = checkpoint_path(Path(task.path))
        try:
            data = read_checkpoint(checkpoint) if checkpoint.exists() else None
        except SoftcellError:
            data = None
        if data is not None:
            last = int(data["next_sample"]) - 1
            grid = sampling_plan(task.params)[0]
            saved.append(f"t = {float(grid[last]):.2f} s of {task.name}")
    where = ", ".join(saved) if saved else "t = 0 s of every unfinished realization"
    return (
        f"interrupted at {where} ({finished} of {total} realizations finished); rerun the "
        "same command to resume"
    )


#: Address schemes of dask.distributed's communication back ends.
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "inproc", "ucx")


def check_scheduler(address: str) -> None:
    """Raise a one-line :class:`SoftcellError` unless ``address`` names a scheduler that
    accepts a connection, at once (dask itself waits 30 s before it gives up)."""
    import socket
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
        parts = None
    if (
        parts is None
        or parts.scheme not in SCHEDULER_SCHEMES
        or (parts.scheme != "inproc" and (not host or port is None))
    ):
        raise SoftcellError(
            f"scheduler address {address!r} is not allowed: must be "
            "SCHEME://HOST:PORT with SCHEME one of "
            f"{', '.join(SCHEDULER_SCHEMES)} (e.g. tcp://10.0.0.5:8786)"
        )
    if parts.scheme == "inproc":
        from distributed.comm.inproc import global_manager

        try:  # an address of another form (IP/PID/N) is no listener either
            listener = global_manager.get_listener_for(address.removeprefix("inproc://"))
        except ValueError:
            listener = None
        if listener is None:
            raise SoftcellError(
                f"no dask scheduler listens at {address!r} in this process (an inproc "
                "address lives in the process that made it; from another one, give tcp://)"
            )
        return
    try:
        with socket.create_connection((host, port), timeout=5) as connection:
            if parts.scheme == "tcp":
                _check_handshake(connection, address)
    except OSError as exc:
        raise SoftcellError(
            f"cannot reach the dask scheduler at {address!r}: {exc.strerror or exc}"
        ) from None


#: The largest first message a dask scheduler is taken to send (its handshake: a few
#: hundred bytes); anything longer is not a scheduler.
HANDSHAKE_BYTES = 1 << 16


def _check_handshake(connection, address: str) -> None:
    """A dask scheduler speaks first: the byte count of its handshake (uint64, little
    endian), then the handshake. Refuse a peer that is silent for 5 s, closes, or states a
    size no handshake has, before dask reads (and allocates) what the peer claims."""

    header = b""
    try:
        while len(header) < 8:
            chunk = connection.recv(8 - len(header))
            if not chunk:
                break
            header += chunk
    except TimeoutError:
        raise SoftcellError(
            f"{address!r} accepts connections but is not a dask scheduler (it said nothing in 5 s)"
        ) from None
    size = int.from_bytes(header, "little") if len(header) == 8 else 0
    if not 0 < size <= HANDSHAKE_BYTES:
        said = (
            f"it closed after {len(header)} bytes"
            if len(header) < 8
            else f"its first message claims {size} bytes, where a dask handshake has at most "
            f"{HANDSHAKE_BYTES}"
        )
        raise SoftcellError(f"{address!r} is not a dask scheduler ({said})")
