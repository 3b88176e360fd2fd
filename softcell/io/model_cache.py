"""The compiled-model cache on disk: where it is, what an entry holds, writing and clearing it.

:mod:`softcell.engine.compiled` keys each composed model and runs its generated source;
this module keeps that source on disk, one directory per *entry*, so that numba caches the
compiled functions beside it like those of any other module::

    <cache>/<label>-<key>/model.py        the generated source, then its origin and checksum
    <cache>/<label>-<key>/entry.json      what it is for (label, components, versions)
    <cache>/<label>-<key>/__pycache__/    numba's own cache files of its functions

Every file is written to a temporary name and renamed (:func:`softcell.io.files.atomic_write`),
so processes starting at once (dask workers) see either no file or a whole one; a corrupt entry
(a truncated file, say) is removed and rebuilt with a :class:`~softcell.errors.CacheWarning`.

Location: ``$SOFTCELL_CACHE_DIR``, else the user cache directory (``platformdirs``), under
``compiled/``.
"""

from __future__ import annotations

import datetime
import functools
import hashlib
import io
import json
import os
import pickletools
import shutil
import warnings
from dataclasses import dataclass
from pathlib import Path

from softcell._version import __version__
from softcell.errors import CacheWarning

#: Environment variable naming the cache's root directory.
CACHE_ENV = "SOFTCELL_CACHE_DIR"

#: Name of the generated source in each entry.
SOURCE = "model.py"

#: The last line of a stored source: where it came from and the checksum of the lines above.
#: The lines above are the source itself, so a traceback's line number is the template's.
_TRAILER = "# softcell compiled model from "


def cache_dir() -> Path:
    """The root of the compiled-model cache (created on first use)."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env).expanduser()
    import platformdirs

    return platformdirs.user_cache_path("softcell") / "compiled"


@dataclass(frozen=True)
class Entry:
    """One entry of the cache, as listed by ``softcell cache``."""

    path: Path
    label: str
    description: str
    created: str
    size: int  # bytes, numba's files included
    stale: bool  # made by another softcell build or numba, numpy, Python version
    damaged: str = ""  # what is wrong with one of its files (rebuilt when next used)

    @property
    def name(self) -> str:
        return self.path.name


def _write(path: Path, text: str) -> None:
    from softcell.io.files import atomic_write  # not at import: importing softcell stays cheap

    with atomic_write(path, makedirs=False) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _normal(source: str) -> str:
    return source if source.endswith("\n") else source + "\n"


def _stored_text(source: str) -> str:
    """What an entry's source file holds: the source, then a line naming its origin (a
    template's path) and the sha256 of the lines above."""
    body = _normal(source)
    origin = getattr(source, "path", "generated source")
    digest = hashlib.sha256(body.encode()).hexdigest()
    return f"{body}{_TRAILER}{origin}; sha256 of the lines above: {digest}\n"


def _checked_source(path: Path) -> str | None:
    """The source of a stored module whose last line matches it, else None."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    if not text.endswith("\n"):
        return None
    head, _, last = text[:-1].rpartition("\n")
    body = head + "\n"
    if not last.startswith(_TRAILER) or not last.endswith(
        hashlib.sha256(body.encode()).hexdigest()
    ):
        return None
    return body


def _pickle_complete(data: bytes) -> None:
    """Raise ValueError unless ``data`` is one or more whole pickles (read opcode by opcode,
    so nothing is imported or built)."""
    stream = io.BytesIO(data)
    while stream.tell() < len(data):
        for opcode, _, _ in pickletools.genops(stream):
            if opcode.name == "STOP":
                break
        else:
            raise ValueError("truncated pickle")


#: Beside each of numba's cache files (``.nbi`` index, ``.nbc`` data) in this cache, a file
#: of the same name plus this suffix holds its sha256, written with it and checked before
#: numba reads it (:class:`_VerifiedCacheFile`): one changed byte in a compiled function's
#: object code unpickles fine and then fails far from its cause.
DIGEST = ".sha256"


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def numba_file_problem(path: Path) -> str | None:
    """What is wrong with one of numba's cache files in this cache, or None: its bytes do not
    match the digest stored beside it, or (a file written before digests were kept) they are
    not whole pickles."""
    try:
        data = path.read_bytes()
        stored = Path(f"{path}{DIGEST}")
        if stored.exists():
            if stored.read_text(encoding="ascii").strip() != _sha256(data):
                return f"{path.name}: its bytes do not match their sha256"
            return None
        _pickle_complete(data)
    except Exception as error:  # any unreadable file is a corrupt entry
        return f"{path.name}: {type(error).__name__}: {error}"
    return None


def _numba_files_ok(folder: Path) -> str | None:
    """None if every numba cache file under ``folder`` is whole, else what is wrong with the
    first that is not."""
    for path in sorted(folder.rglob("*.nb[ic]")):
        problem = numba_file_problem(path)
        if problem is not None:
            return problem
    return None


def _matches_digest(path: str) -> bool:
    """Whether numba's cache file ``path`` matches its stored digest (False, with a warning,
    when it does not; False, silently, when it has none: written by a process that stopped
    between the two files, or before digests were kept)."""
    try:
        data = Path(path).read_bytes()
        stored = Path(f"{path}{DIGEST}").read_text(encoding="ascii").strip()
    except OSError:
        return False
    if stored == _sha256(data):
        return True
    warnings.warn(
        f"softcell: numba's cache file {path} does not match its sha256 (damaged); "
        "compiling it again",
        CacheWarning,
        stacklevel=4,
    )
    return False


def _verified_cache_file(base: type) -> type:
    """numba's ``IndexDataCacheFile`` (``base``), made to keep a sha256 beside each file it
    writes in this cache and to check it before reading: a file that does not match is
    reported (:class:`~softcell.errors.CacheWarning`) and treated as absent, so numba compiles
    the function again and rewrites it. Files elsewhere (other projects' caches) are read and
    written as numba does."""

    class VerifiedCacheFile(base):  # type: ignore[misc, valid-type]
        def __init__(self, cache_path, filename_base, source_stamp):
            super().__init__(cache_path, filename_base, source_stamp)
            try:
                self._verified = Path(cache_path).resolve().is_relative_to(cache_dir().resolve())
            except OSError:
                self._verified = False

        def _seal(self, path: str) -> None:
            with self._open_for_write(f"{path}{DIGEST}") as f:
                f.write(_sha256(Path(path).read_bytes()).encode("ascii"))

        def _load_index(self):
            if self._verified and os.path.exists(self._index_path):
                if not _matches_digest(self._index_path):
                    return {}
            return super()._load_index()

        def _save_index(self, overloads):
            super()._save_index(overloads)
            if self._verified:
                self._seal(self._index_path)

        def _load_data(self, name):
            if self._verified and not _matches_digest(self._data_path(name)):
                raise OSError(f"{name} is not verified")  # numba: not in the cache
            return super()._load_data(name)

        def _save_data(self, name, data):
            super()._save_data(name, data)
            if self._verified:
                self._seal(self._data_path(name))

    VerifiedCacheFile.__qualname__ = VerifiedCacheFile.__name__ = "VerifiedCacheFile"
    return VerifiedCacheFile


@functools.cache
def _verify_numba_files() -> None:
    """Have numba keep and check a digest of each of its cache files in this cache (numba
    offers no public hook: its caches make their files through the module's
    ``IndexDataCacheFile``, replaced here by a subclass that changes nothing elsewhere)."""
    from numba.core import caching

    caching.IndexDataCacheFile = _verified_cache_file(caching.IndexDataCacheFile)


def _entry_problem(folder: Path, source: str) -> str | None:
    """What is wrong with an existing entry for ``source``, or None (also when it is absent,
    or was removed meanwhile by a process repairing it: then it is written again)."""
    path = folder / SOURCE
    if not path.exists():
        return None
    body = _checked_source(path)
    if body is None and not path.exists():
        return None
    if body != _normal(source):
        return f"{SOURCE} does not match its checksum"
    return _numba_files_ok(folder / "__pycache__")


class DiskStore:
    """The store of generated modules that :mod:`softcell.engine.compiled` uses: one
    entry per key under :func:`cache_dir` (read when each module is placed, so
    ``$SOFTCELL_CACHE_DIR`` may change within a session)."""

    def location(self, label: str, key: str) -> str:
        """The path of the source file of the entry of ``key``."""
        return str(cache_dir() / f"{label}-{key[:20]}" / SOURCE)

    def place(self, label: str, key: str, source: str, description: str) -> str:
        """Make the entry of ``key`` hold a whole, readable copy of ``source``, repairing a
        corrupt one, and return the path of its source file.

        Other processes may be writing the same entry at the same time (dask workers
        starting together): they write the same bytes, each file by an atomic rename, so a
        file is either absent or whole, and only a file that is there and wrong is corrupt.

        Raises
        ------
        OSError, softcell.errors.SoftcellError
            When the cache cannot be written.
        """
        path = Path(self.location(label, key))
        folder = path.parent
        _verify_numba_files()
        problem = _entry_problem(folder, source)
        if problem is not None:
            warnings.warn(
                f"softcell: the compiled-model cache entry {folder} is corrupt "
                f"({problem}); rebuilding it",
                CacheWarning,
                stacklevel=4,
            )
            shutil.rmtree(folder / "__pycache__", ignore_errors=True)
            path.unlink(missing_ok=True)
        folder.mkdir(parents=True, exist_ok=True)
        if not path.exists():
            _write(folder / "entry.json", json.dumps(_meta(label, description), indent=1) + "\n")
            _write(path, _stored_text(source))
        return str(path)

    def cache_kernels(self) -> None:
        """Have numba keep the cache files of softcell's own compiled functions (kernels,
        built-in components) in the entry :data:`KERNELS` of this cache, not beside their
        sources in site-packages, so that ``softcell cache clear`` removes them too; and
        have numba check each of its cache files in this cache before reading it."""
        _verify_numba_files()
        _use_kernel_locator()


#: The label of the entry holding numba's cache files of softcell's own compiled functions,
#: in folders named as the package's (``kernels-<code>/engine/kernels``,
#: ``kernels-<code>/builtins``, ...). numba checks each file against its own function's
#: source and its own version, not against the functions it calls in other files (an edit of
#: the ellipse distance would leave the contact's cached code as it was), so the entry is
#: named by a digest of softcell's compiled parts: edited code gets a new entry. It is stale
#: when made by another softcell, numba or code.
KERNELS = "kernels"

_PACKAGE = Path(__file__).resolve().parents[1]


@functools.cache
def _kernel_code() -> str:
    """A digest of softcell's compiled parts (the files compiled code is made of), read once
    per process."""
    from softcell.engine.compiled import package_hash

    return package_hash("softcell")[:20]


def kernel_entry(root: Path | None = None) -> Path:
    """The folder of numba's cache files of softcell's own compiled functions (the entry
    labelled :data:`KERNELS` for this code) in the cache ``root`` (default: the cache)."""
    return (cache_dir() if root is None else root) / f"{KERNELS}-{_kernel_code()}"


def _kernel_meta() -> dict[str, str]:
    import numba

    return {
        "label": KERNELS,
        "description": "softcell's own compiled functions (numba's cache files)",
        "softcell": __version__,
        "numba": numba.__version__,
        "code": _kernel_code(),
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
    }


@functools.cache
def _use_kernel_locator() -> None:
    """Put a numba cache locator for the files of the softcell package first in numba's
    list (numba offers no public hook; its locators are tried in order, and this one declines
    every other file, and any file when the cache cannot be written, as numba's own do)."""
    from numba.core import caching

    class KernelCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            folder = Path(py_file).resolve().parent.relative_to(_PACKAGE)
            self._cache_path = str(kernel_entry() / folder)

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            if not Path(py_file).resolve().is_relative_to(_PACKAGE):
                return None
            entry = kernel_entry()
            try:
                if _marker(entry) is None:
                    entry.mkdir(parents=True, exist_ok=True)
                    _write(entry / "entry.json", json.dumps(_kernel_meta(), indent=1) + "\n")
            except OSError:
                return None
            return super().from_function(py_func, py_file)

    caching.CacheImpl._locator_classes.insert(0, KernelCacheLocator)


def _meta(label: str, description: str) -> dict[str, str]:
    import numba

    from softcell.engine.compiled import environment_key

    return {
        "label": label,
        "description": description,
        "softcell": __version__,
        "numba": numba.__version__,
        "environment": environment_key(),
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
    }


def _marker(folder: Path) -> dict[str, str] | None:
    """The entry marker (``entry.json``) softcell writes first into each entry it makes, or
    None when ``folder`` has no valid one."""
    try:
        meta = json.loads((folder / "entry.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    # Entries of every softcell build since the cache exists carry a label and a date.
    return meta if isinstance(meta, dict) and {"label", "created"} <= set(meta) else None


def foreign(root: Path) -> list[Path]:
    """What ``root`` holds that softcell did not make: files, and folders that are neither
    an entry (a valid marker) nor empty."""
    if not root.is_dir():
        return []
    found = []
    for path in sorted(root.iterdir()):
        if path.is_dir() and not path.is_symlink():
            if _marker(path) is not None or not any(path.iterdir()):
                continue
        found.append(path)
    return found


def entries(root: Path | None = None) -> list[Entry]:
    """The cache's entries, oldest first: the folders with softcell's entry marker (anything
    else in the folder is no entry, see :func:`foreign`)."""
    from softcell.engine.compiled import environment_key

    root = cache_dir() if root is None else root
    out: list[Entry] = []
    if not root.is_dir():
        return out
    current = environment_key()
    for folder in sorted(p for p in root.iterdir() if p.is_dir() and not p.is_symlink()):
        meta = _marker(folder)
        if meta is None:
            continue
        size = sum(f.stat().st_size for f in folder.rglob("*") if f.is_file())
        out.append(
            Entry(
                folder,
                str(meta["label"]),
                str(meta.get("description", "")),
                str(meta["created"]),
                size,
                _stale(meta, current),
                _numba_files_ok(folder) or "",
            )
        )
    return sorted(out, key=lambda e: e.created)


def _stale(meta: dict[str, str], environment: str) -> bool:
    import numba

    if meta["label"] == KERNELS:
        made = (meta.get("softcell"), meta.get("numba"), meta.get("code"))
        return made != (__version__, numba.__version__, _kernel_code())
    return meta.get("environment") != environment


def clear(root: Path | None = None, stale_only: bool = False) -> int:
    """Remove every entry (only the stale and the damaged ones with ``stale_only``); return
    how many were removed. Processes running from an entry keep what they loaded.

    Raises
    ------
    SoftcellError
        Before removing anything, when ``root`` holds what softcell did not make (it is not
        a cache: ``$SOFTCELL_CACHE_DIR`` pointing at a results folder); after trying, when
        an entry could not be removed (a read-only cache), naming the first.
    """
    from softcell.errors import SoftcellError

    root = cache_dir() if root is None else root
    strangers = foreign(root)
    if strangers:
        raise SoftcellError(
            f"{root} is not a softcell cache: it holds {len(strangers)} item(s) softcell did "
            f"not make (e.g. {strangers[0].name}); nothing removed (check "
            f"${CACHE_ENV})"
        )
    found = [e for e in entries(root) if e.stale or e.damaged or not stale_only]
    failed: list[str] = []
    for entry in found:
        try:
            shutil.rmtree(entry.path)
        except OSError as exc:
            failed.append(f"{type(exc).__name__}: {exc.strerror or exc}")
    left = [e for e in found if e.path.exists()]
    if left:
        why = failed[0] if failed else "it is still there"
        raise SoftcellError(
            f"could not remove {len(left)} of {len(found)} entries from {root} "
            f"(first: {left[0].path.name}: {why}); {len(found) - len(left)} removed"
        )
    return len(found)
