"""Files, safely: one atomic-write helper for every writer, and one rule for every output.

Every file softcell writes (NetCDF, video, figures, report, checkpoints) goes through
:func:`atomic_write` or :func:`atomic_files`: it is written under a hidden temporary name that
is unique to the process, flushed to disk, checked, and only then renamed to its final name; on
any failure the temporary file is removed and the final name keeps what it had. A full disk, a
read-only file system or a missing permission is reported as such, in one line
(:class:`StorageError`).

:func:`check_output` is the one rule of every verb's ``-o``: an output never replaces one of
the inputs (the same file, or a file inside an input directory), never replaces a file that is
not a softcell output of the same kind unless ``overwrite`` is given, and its directory must be
writable, all checked before anything is computed.
"""

from __future__ import annotations

import errno
import fcntl
import functools
import hashlib
import json
import math
import os
import re
import secrets
import shutil
import socket
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

from softcell.engine.interrupt import deferred, shielded
from softcell.errors import SoftcellError
from softcell.model.limits import human_bytes

#: The kinds of output, and how an existing file of that kind is recognised.
KINDS = ("simulation", "tracking", "analysis", "video", "figure", "report", "export", "fit")
#: The kinds of output that are NetCDF files, marked by their ``softcell_origin``.
NETCDF_KINDS = ("simulation", "tracking", "analysis", "export", "fit")

#: Below this many free bytes a failed write is taken to be a full disk.
FULL_DISK_BYTES = 1 << 20


class StorageError(SoftcellError):
    """A file could not be written: full disk, read-only file system, no permission."""


def no_input(path: str | os.PathLike[str], what: str = "file") -> SoftcellError:
    """The error for an input ``path`` that is no readable ``what`` (e.g. "video file"):
    missing, a directory, or something else that is not a regular file."""
    path = Path(path)
    if path.is_dir():
        return SoftcellError(f"{path} is a directory, not a {what}")
    if path.exists():
        return SoftcellError(f"{path} is not a regular file, so no {what}")
    return SoftcellError(f"no such {what}: {path}")


#: The longest file name most file systems take, in bytes.
NAME_MAX = 255

#: A temporary name of :func:`temporary_path`: its target's name, the writer's pid and host
#: (a digest; absent in names of softcell 0.2), a random token.
_TEMPORARY = re.compile(
    r"^\.(?P<stem>.+)\.(?P<pid>\d+)-(?:(?P<host>[0-9a-f]{4})-)?[0-9a-f]{6}\.tmp(\.[^.]*)?$"
)

_swept: set[Path] = set()  # folders whose leftovers this process has removed


@functools.cache
def _host() -> str:
    return hashlib.sha1(socket.gethostname().encode()).hexdigest()[:4]


def temporary_path(path: str | os.PathLike[str]) -> Path:
    """A hidden name beside ``path``, unique to this process and call, keeping the suffix
    (``.name.<pid>-<host>-<token>.tmp.nc``): writers that infer the format from it still can,
    and sweep readers skip it (hidden). A name too long for the file system with these parts
    keeps its start and a digest of the rest."""
    path = Path(path)
    tail = f".{os.getpid()}-{_host()}-{secrets.token_hex(3)}.tmp{path.suffix}"
    stem = path.stem
    room = NAME_MAX - len(tail.encode()) - 1
    if len(stem.encode()) > room:
        digest = hashlib.sha1(stem.encode()).hexdigest()[:12]
        stem = stem.encode()[: room - 13].decode(errors="ignore") + "~" + digest
    return path.with_name(f".{stem}{tail}")


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: it exists
        return True
    return True


def remove_leftovers(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files that writers on this host left in ``directory`` when they
    were killed (their pid, which the name records, runs no more); return them. Files of
    running processes and of other hosts (a cluster's workers share the folder) are kept."""
    removed = []
    try:
        found = [e for e in os.scandir(directory) if e.name.startswith(".") and ".tmp" in e.name]
    except OSError:
        return removed
    for entry in found:
        match = _TEMPORARY.match(entry.name)
        if match is None or match["host"] not in (None, _host()) or not entry.is_file():
            continue
        pid = int(match["pid"])
        if pid != os.getpid() and not _running(pid):
            with suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


def _sweep_once(directory: Path) -> None:
    """:func:`remove_leftovers` of ``directory``, once per process."""
    key = Path(os.path.abspath(directory))
    if key not in _swept:
        _swept.add(key)
        remove_leftovers(key)


def _existing_ancestor(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def free_bytes(path: str | os.PathLike[str]) -> int:
    """Bytes available to this user on the file system that holds (or would hold) ``path``."""
    st = os.statvfs(_existing_ancestor(Path(path)))
    return st.f_bavail * st.f_frsize


def _read_only(path: Path) -> bool:
    return bool(os.statvfs(_existing_ancestor(path)).f_flag & os.ST_RDONLY)


def storage_problem(
    path: str | os.PathLike[str], exc: BaseException | None = None, need: int = FULL_DISK_BYTES
) -> str | None:
    """Why writing ``path`` failed, if the file system says: ``"no space left on device"``,
    ``"read-only file system"``, ``"permission denied"``, or None.

    Libraries that lose the ``errno`` (netCDF's "HDF error", OpenCV's silent writer) are
    diagnosed from the file system itself: read-only flag, free space below ``need`` bytes
    (1 MiB by default).
    """
    path = Path(path)
    code = getattr(exc, "errno", None)
    if code in (errno.ENOSPC, errno.EDQUOT):
        return "no space left on device"
    if code == errno.EROFS:
        return "read-only file system"
    if code in (errno.EACCES, errno.EPERM):
        return "permission denied"
    try:
        if _read_only(path):
            return "read-only file system"
        if free_bytes(path) < need:
            return "no space left on device"
    except OSError:
        return None
    return None


def _error(path: Path, problem: str) -> StorageError:
    where = _existing_ancestor(path.parent)
    return StorageError(
        f"cannot write {path}: {problem} ({human_bytes(free_bytes(where))} free in {where})"
        if problem == "no space left on device"
        else f"cannot write {path}: {problem}"
    )


def _fsync_directory(directory: Path) -> None:
    with suppress(OSError):  # not every file system lets a directory be opened
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _commit(tmp: Path, path: Path) -> None:
    with open(tmp, "rb+") as fh:
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    _fsync_directory(path.parent)


def default_mode(path: str | os.PathLike[str]) -> None:
    """Give ``path`` the permissions ``open`` gives a new file (0666 less the umask), for the
    writers that choose their own (gsd: 0640)."""
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(path, 0o666 & ~mask)


@contextmanager
def atomic_files(*, makedirs: bool = True) -> Iterator[_Staging]:
    """Write several files all or nothing.

    ``staging.path(final)`` gives the temporary name to write ``final`` under; when the block
    ends without an error, every staged file is flushed and renamed to its final name. On any
    error (including a full disk) every temporary file is removed, no final name changes, and
    a :class:`StorageError` says why when the file system is the cause.
    """
    staging = _Staging(makedirs)
    try:
        yield staging
        with deferred():  # a stop signal stops the run once every file has its final name
            for tmp, path in staging.files:
                if not tmp.exists():
                    raise SoftcellError(f"internal error: {path} was staged but not written")
                with open(tmp, "rb+") as fh:
                    os.fsync(fh.fileno())
            for tmp, path in staging.files:
                os.replace(tmp, path)
            for directory in {p.parent for _, p in staging.files}:
                _fsync_directory(directory)
    except BaseException as exc:
        with shielded():  # nothing interrupts the removal of the temporary files
            for tmp, _ in staging.files:
                with suppress(OSError):
                    tmp.unlink(missing_ok=True)
            for directory in reversed(staging.created):
                with suppress(OSError):
                    directory.rmdir()  # only if still empty
        if isinstance(exc, StorageError | KeyboardInterrupt):
            raise
        for _, path in staging.files:
            problem = storage_problem(path, exc)
            if problem:
                raise _error(path, problem) from None
        raise


class _Staging:
    def __init__(self, makedirs: bool) -> None:
        self.files: list[tuple[Path, Path]] = []
        self.created: list[Path] = []  # directories made here, removed again on failure
        self.makedirs = makedirs

    def path(self, final: str | os.PathLike[str]) -> Path:
        final = Path(final)
        if final.is_dir():
            raise SoftcellError(f"cannot write {final}: it is a directory")
        _check_name_length(final, "cannot write")
        if self.makedirs:
            missing = [p for p in (final.parent, *final.parent.parents) if not p.exists()]
            self.created.extend(reversed(missing))
            try:
                final.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise _error(final, storage_problem(final, exc) or str(exc)) from None
        _sweep_once(final.parent)
        tmp = temporary_path(final)
        self.files.append((tmp, final))
        return tmp


@contextmanager
def atomic_write(path: str | os.PathLike[str], *, makedirs: bool = True) -> Iterator[Path]:
    """Write one file atomically: the block writes the yielded temporary path, which becomes
    ``path`` once the block ends without an error (see :func:`atomic_files`)."""
    with atomic_files(makedirs=makedirs) as staging:
        yield staging.path(path)


def _json_ready(value: Any) -> Any:
    """``value`` with every non-finite float (numpy's too) made None, containers walked."""
    if isinstance(value, dict):
        return {k: _json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_text(value: Any, **options: Any) -> str:
    """``value`` as JSON text that every reader takes: NaN and infinities, which Python's
    ``json`` writes but JSON has not, written as ``null`` (none measured). ``options`` as
    for :func:`json.dumps`."""
    return json.dumps(_json_ready(value), allow_nan=False, **options)


# -- the rule of every output ---------------------------------------------------------------


def kind_of(path: str | os.PathLike[str]) -> str | None:
    """The kind of softcell output an existing file is (one of :data:`KINDS`), or None when
    it is not recognisably one (videos carry no mark, so they are always None)."""
    path = Path(path)
    suffix = path.suffix.lower()
    try:
        if suffix == ".nc":
            import netCDF4

            with netCDF4.Dataset(path) as nc:
                origin = getattr(nc, "softcell_origin", None)
            return origin if origin in NETCDF_KINDS else None
        if suffix in (".png", ".pdf", ".svg"):
            size = path.stat().st_size
            with open(path, "rb") as fh:
                head = fh.read(1 << 16)
                fh.seek(max(size - (1 << 16), 0))
                tail = fh.read()
            return "figure" if b"softcell " in head or b"softcell " in tail else None
        if suffix in (".md", ".html", ".json"):
            with open(path, "rb") as fh:
                head = fh.read(4096)
            marks = (b"softcell reproduction report", b'"softcell_version"')
            return "report" if any(m in head for m in marks) else None
        if suffix == ".gsd":
            return "export" if gsd_attributes(path) else None
    except (OSError, RuntimeError, ValueError):
        return None
    return None


def _inside(path: Path, directory: Path) -> bool:
    try:
        path.relative_to(directory)
    except ValueError:
        return False
    return True


def _check_apart_from_input(path: Path, source: Path, directory: bool, option: str) -> None:
    """Raise unless the output ``path`` is neither the input ``source``, nor inside it, nor
    (for a directory output) holding it."""
    if not source.exists():
        return
    if path.exists() and os.path.samefile(path, source):
        raise SoftcellError(
            f"{option} {path} is the input {source}: an output never "
            "replaces an input; choose another name"
        )
    if source.is_dir() and _inside(path.resolve(), source.resolve()):  # through links too
        raise SoftcellError(
            f"{option} {path} is inside the input directory {source}: an "
            "output there would be read as part of it; write it elsewhere"
        )
    if directory and source.is_file() and _inside(source.resolve(), path.resolve()):
        raise SoftcellError(
            f"{option} {path} holds the input {source}: write the outputs to another directory"
        )


def _check_replaceable(path: Path, kind: str, option: str) -> None:
    """Raise unless the existing file ``path`` is a softcell output of ``kind`` (a rerun)."""
    found = kind_of(path)
    if found == kind:
        return
    if kind == "video":
        what = "exists (a video carries no mark of who made it)"
    elif found:
        what = f"exists and is a softcell {found} file"
    else:
        what = f"exists and is not a softcell {kind} file"
    raise SoftcellError(f"{option} {path} {what}; pass --overwrite to replace it")


def _check_name_length(path: Path, what: str) -> None:
    """Refuse a path with a part longer than the file system takes (:data:`NAME_MAX`)."""
    for part in path.parts:
        size = len(part.encode())
        if size > NAME_MAX:
            raise SoftcellError(
                f"{what} {part[:32]}...: that name is {size} bytes long, and file systems "
                f"take at most {NAME_MAX}"
            )


def check_output(
    path: str | os.PathLike[str],
    kind: str,
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
    overwrite: bool = False,
    directory: bool = False,
    option: str = "-o",
) -> Path:
    """Check, before anything is computed, that ``path`` may receive an output of ``kind``.

    Parameters
    ----------
    path : path-like
        The output: a file, or with ``directory`` a folder of outputs.
    kind : str
        One of :data:`KINDS`: an existing file is replaced only if it is a softcell output of
        this kind (a rerun), or with ``overwrite``.
    inputs : paths
        The command's inputs (files or sweep directories); the output may never be one of
        them, nor lie inside an input directory, nor (for a directory output) contain one.
    overwrite : bool
        Replace an existing file that is not a softcell output of ``kind``.

    Returns
    -------
    Path
        ``path``, absolute.

    Raises
    ------
    SoftcellError
        One line naming the output, the problem and the way out.
    """
    path = Path(os.path.abspath(path))
    _check_name_length(path, option)
    for source in inputs:
        _check_apart_from_input(path, Path(os.path.abspath(source)), directory, option)
    if directory:
        if path.exists() and not path.is_dir():
            raise SoftcellError(f"{option} {path} is an existing file, not a directory")
    elif path.is_dir():
        raise SoftcellError(
            f"{option} {path} is a directory; give a file name "
            f"(e.g. {path / ('out.mkv' if kind == 'video' else 'out.nc')})"
        )
    elif path.exists() and not overwrite:
        _check_replaceable(path, kind, option)
    check_writable(path if directory else path.parent)
    return path


def check_writable(directory: str | os.PathLike[str], need: int = 0) -> None:
    """Raise :class:`StorageError` unless files can be created in ``directory`` (or, when it
    does not exist yet, in its nearest existing ancestor) with ``need`` bytes free."""
    directory = Path(os.path.abspath(directory))
    base = _existing_ancestor(directory)
    if not base.is_dir():
        raise SoftcellError(f"cannot create directory {directory}: {base} is a file")
    if _read_only(base):
        raise StorageError(f"cannot write to {directory}: read-only file system")
    if not os.access(base, os.W_OK | os.X_OK):
        raise StorageError(f"cannot write to {directory}: permission denied")
    free = free_bytes(base)
    if need and free < need:
        raise StorageError(
            f"cannot write to {directory}: no space left on device (the run "
            f"needs about {human_bytes(need)}, {human_bytes(free)} free)"
        )


#: The lock file of an output folder being written (hidden: sweep readers skip it).
LOCK_FILE = ".softcell.lock"


def _holder(lock: Path) -> str:
    try:
        who = json.loads(lock.read_text(encoding="utf-8"))
        since = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(who["since"]))
        return f"{who['command']} (pid {who['pid']} on {who['host']}, since {since})"
    except (OSError, ValueError, KeyError, TypeError):
        return "another softcell command"


@contextmanager
def folder_lock(directory: str | os.PathLike[str], command: str) -> Iterator[Path]:
    """Hold ``directory`` for one writer: a second command writing there meanwhile is
    refused at once, in one line naming the holder.

    The lock is an exclusive ``flock`` on :data:`LOCK_FILE` in ``directory``, which records
    the holder's command, pid, host and start. The operating system releases it when the
    holder ends in any way (even ``kill -9``), so a lock is never stale; the file is removed
    when the block ends. Two holders in one process exclude each other too. A file system
    that cannot lock is refused rather than left unguarded.

    Parameters
    ----------
    directory : path-like
        An existing folder.
    command : str
        What holds it, as the refusal names it (e.g. ``"softcell simulate"``).

    Yields
    ------
    Path
        The lock file.

    Raises
    ------
    SoftcellError
        When another process holds the folder, or it cannot be locked.
    """
    lock = Path(directory) / LOCK_FILE
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise _error(lock, storage_problem(lock, exc) or str(exc)) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EACCES, errno.EAGAIN):
                raise SoftcellError(
                    f"{directory} is being written by {_holder(lock)}; wait for it to end, "
                    "or write to another directory"
                ) from None
            raise SoftcellError(f"cannot lock {directory} ({exc.strerror})") from None
        # The holder before us may have removed the file as we opened it: lock the file
        # that is there now, not an orphan.
        try:
            current = os.stat(lock).st_ino
        except FileNotFoundError:
            current = None
        if current == os.fstat(fd).st_ino:
            break
        os.close(fd)
    try:
        remove_leftovers(directory)
        os.ftruncate(fd, 0)
        me = {"command": command, "pid": os.getpid(), "host": socket.gethostname()}
        os.write(fd, json.dumps({**me, "since": time.time()}).encode())
        yield lock
    finally:
        with shielded():
            with suppress(OSError):
                lock.unlink()  # before the lock goes: whoever opens it next sees it is gone
            os.close(fd)


def folder_in_use(directory: str | os.PathLike[str]) -> str | None:
    """Who is writing ``directory`` now (see :func:`folder_lock`), or None when nobody is.

    A reader asks before it reads a folder: while a command writes there, the folder holds
    only part of what it will.
    """
    lock = Path(directory) / LOCK_FILE
    try:
        fd = os.open(lock, os.O_RDONLY)
    except OSError:
        return None  # no lock file: nobody writes there
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError as exc:
        if exc.errno in (errno.EACCES, errno.EAGAIN):
            return _holder(lock)
        return None  # a file system that cannot lock: folder_lock refuses to write there
    finally:
        os.close(fd)  # closing releases a shared lock we took
    return None


def remove(paths: Iterable[str | os.PathLike[str]]) -> None:
    """Delete files and directories (``--overwrite`` of stale outputs)."""
    for path in map(Path, paths):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink(missing_ok=True)


def gsd_attributes(path: str | os.PathLike[str]) -> dict | None:
    """The softcell attributes frame 0 of a GSD file logs.

    Parameters
    ----------
    path : path-like
        A GSD file.

    Returns
    -------
    dict or None
        The attributes of the simulation file it was exported from (parameters, seed,
        components, version), None when frame 0 logs none.
    """
    import gsd.hoomd

    with gsd.hoomd.open(path, "r") as trajectory:
        if len(trajectory) == 0:
            return None
        raw = trajectory[0].log.get("softcell/attributes")
    import numpy as np

    return None if raw is None else json.loads(np.asarray(raw, dtype=np.uint8).tobytes())
