"""The compiled-model cache: composed models keyed by their code, so numba caches them.

numba caches a compiled function by its source file, so each composition of the chosen
components (the sum of the energy terms, the right-hand side, the time loop) is generated as
the source of a real module, stored by a :class:`ModuleStore` (the disk cache of
:mod:`softcell.io.model_cache`, set when softcell is imported) and run from there.

The functions it calls (the components' kernels, constants, other entries' functions) are
*bound* into the module's namespace before it runs. numba does not look at those bindings
when it replays a cached function, so the key covers them: the source, each bound kernel's
code (every Python file of its package), its distribution's version, and the versions of
softcell, numba, numpy and Python. A changed plugin gives a new key, hence a new entry; a
stale entry is never read.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import importlib.metadata
import os
import platform
import sys
import threading
import types
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Protocol

import numba
import numpy as np
from numba.core.registry import CPUDispatcher

from softcell._version import __version__
from softcell.errors import CacheWarning, ContractError, SoftcellError
from softcell.settings import JIT, module_store

# numba flags of the generated functions: the kernels' own, cached on disk, or not cached
# where an entry cannot be keyed (see :class:`NotCacheable`). The loader binds them as
# ``JIT_FLAGS``, and as ``LEAN_JIT_FLAGS`` without numba's reference counting (``_nrt``) for
# functions that never allocate: counting the references of the workspaces' arrays at every
# call cost a sixth of a rodas4 step.
_CACHED = {**JIT, "cache": True}
_UNCACHED = {**JIT, "cache": False}

#: The package the generated modules are registered under in ``sys.modules``.
_PARENT = "softcell_compiled"

_LOCK = threading.Lock()
_LOADED: dict[str, types.ModuleType] = {}  # by the location of their source
_KEYS: dict[int, str] = {}  # id of a generated function -> key of its entry


class NotCacheable(Exception):
    """A binding whose code cannot be identified, so an entry holding it cannot be keyed."""


#: The parts of softcell that compiled code is made of (kernels, the built-in components,
#: templates, numba flags); a change elsewhere (the CLI, the analysis) keeps the cache.
COMPILED_PARTS = ("settings.py", "engine", "builtins", "integrators")


def _source_files(top: str) -> list[Path]:
    """The Python files of the top-level package (or module) ``top``; for softcell, those of
    its :data:`COMPILED_PARTS`."""
    module = sys.modules.get(top)
    paths = list(getattr(module, "__path__", []) or [])
    if not paths:
        file = getattr(module, "__file__", None)
        if not file or not os.path.exists(file):
            raise NotCacheable(f"module {top!r} has no source file")
        return [Path(file)]
    files: list[Path] = []
    for root in paths:
        if top == "softcell":
            for part in COMPILED_PARTS:
                path = Path(root, part)
                files += [path] if path.suffix == ".py" else sorted(path.rglob("*.py"))
        else:
            files += sorted(Path(root).rglob("*.py"))
    return files


def package_hash(top: str) -> str:
    """sha256 of :func:`_source_files` of ``top``, names and contents (re-read whenever a
    file's size or time changes, so a plugin edited and reloaded in a session gets a new
    key)."""
    files = _source_files(top)
    stamps = tuple((str(f), f.stat().st_mtime_ns, f.stat().st_size) for f in files)
    return _hash_files(stamps)


@functools.lru_cache(maxsize=256)
def _hash_files(stamps: tuple[tuple[str, int, int], ...]) -> str:
    digest = hashlib.sha256()
    for name, _, _ in stamps:
        digest.update(os.path.basename(name).encode())
        digest.update(Path(name).read_bytes())
    return digest.hexdigest()


def code_digest(obj: object) -> str:
    """The first 16 hex digits of :func:`package_hash` of the package that defines ``obj``
    (a component class), or ``"unidentified (REASON)"`` when that package has no source
    files (a class typed in a notebook)."""
    top = str(getattr(obj, "__module__", "")).partition(".")[0]
    try:
        return package_hash(top)[:16]
    except NotCacheable as reason:
        return f"unidentified ({reason})"


@functools.cache
def _distribution_version(top: str) -> str:
    """The version of ``top``: its distribution's of the same name, else its ``__version__``
    (the code itself is keyed by :func:`package_hash`)."""
    try:
        return importlib.metadata.version(top)
    except importlib.metadata.PackageNotFoundError:
        return str(getattr(sys.modules.get(top), "__version__", ""))


def _fingerprint(name: str, value: object) -> str:
    """What identifies a binding's behaviour, as text for the key."""
    if value is None or isinstance(value, bool | int | float | str):
        return f"{name}={value!r}"
    if isinstance(value, CPUDispatcher):
        key = _KEYS.get(id(value))
        if key is not None:
            return f"{name}=entry:{key}"
        func = value.py_func
        qualname = func.__qualname__
        if "<locals>" in qualname or "<lambda>" in qualname:
            raise NotCacheable(
                f"{func.__module__}.{qualname} is a closure: its behaviour "
                "depends on values the cache cannot see"
            )
        top = func.__module__.split(".")[0]
        if sys.modules.get(func.__module__) is None or top == "__main__":
            raise NotCacheable(
                f"{func.__module__}.{qualname} is not defined in an importable module"
            )
        return (
            f"{name}={func.__module__}:{qualname}:{package_hash(top)}:{_distribution_version(top)}"
        )
    raise TypeError(
        f"cannot bind {name!r} = {value!r} into a compiled module: only "
        "compiled functions and scalars can be bound"
    )


#: Imports of generated sources that the environment's versions already cover.
_KEYED_BY_VERSION = {"softcell", "numba", "numpy", "rocket_fft", "llvmlite"}


def _imported_packages(source: str) -> list[str]:
    """The top-level packages ``source`` imports whose code the key must cover (a plugin's
    own helpers, say): every one but the standard library's and those of the environment."""
    tops = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            tops.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            tops.add(node.module.split(".")[0])
    tops -= _KEYED_BY_VERSION | set(sys.stdlib_module_names)
    for top in tops:
        importlib.import_module(top)
    return sorted(tops)


def _environment() -> str:
    return (
        f"softcell={__version__}:{package_hash('softcell')};numba={numba.__version__};"
        f"numpy={np.__version__};python={sys.version};{platform.machine()}"
    )


def environment_key() -> str:
    """sha256 of what every entry's key shares: softcell's code and the versions of softcell,
    numba, numpy and Python. An entry made under another is stale: never read again."""
    return hashlib.sha256(_environment().encode()).hexdigest()


def entry_key(source: str, bindings: Mapping[str, object]) -> str:
    """The key of the entry holding ``source`` with ``bindings`` (hex sha256).

    Raises
    ------
    NotCacheable
        When a bound function's code cannot be identified (a closure, a notebook cell).
    """
    parts = [_environment(), source]
    parts += [_fingerprint(n, bindings[n]) for n in sorted(bindings)]
    parts += [
        f"import {top}:{package_hash(top)}:{_distribution_version(top)}"
        for top in _imported_packages(source)
    ]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


class ModuleStore(Protocol):
    """Where generated modules are kept between processes (:mod:`softcell.io.model_cache`)."""

    def location(self, label: str, key: str) -> str:
        """The path the source of ``key`` has, or will have, in the store."""

    def place(self, label: str, key: str, source: str, description: str) -> str:
        """Store ``source`` under ``key`` (once; repaired when corrupt) and return its
        :meth:`location`, from which the module runs and beside which numba caches it.
        Raises OSError or :class:`~softcell.errors.SoftcellError` when it cannot write."""


def _execute(
    name: str,
    filename: str,
    source: str,
    bindings: Mapping[str, object],
    flags: Mapping[str, object],
) -> types.ModuleType:
    if _PARENT not in sys.modules:
        parent = types.ModuleType(_PARENT)
        parent.__path__ = []  # a namespace for the generated modules, so pickles find them
        sys.modules[_PARENT] = parent
    module = types.ModuleType(name)
    module.__file__ = filename
    module.__dict__.update(bindings)
    module.__dict__["JIT_FLAGS"] = dict(flags)
    module.__dict__["LEAN_JIT_FLAGS"] = {**flags, "_nrt": False}
    # The stored file holds the source line for line (its origin and checksum follow it), so
    # tracebacks name the template's own line numbers.
    code = compile(source, filename, "exec")
    sys.modules[name] = module
    exec(code, module.__dict__)
    return module


def _in_memory(label: str, source: str, bindings: Mapping[str, object]) -> types.ModuleType:
    """The module compiled in this process only (not cacheable or no writable cache)."""
    return _execute(
        f"{_PARENT}.{label.replace('-', '_')}_{id(source)}",
        f"<softcell {label}>",
        source,
        bindings,
        _UNCACHED,
    )


def _declared_bindings(source: str) -> tuple[str, ...] | None:
    """The names a template declares in its top-level ``BOUND = (...)``, or None."""
    for node in ast.parse(source).body:
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id == "BOUND"
        ):
            return tuple(ast.literal_eval(node.value))
    return None


def check_bindings(label: str, source: str, bindings: Mapping[str, object]) -> None:
    """Raise :class:`~softcell.errors.ContractError` unless ``bindings`` are exactly the names
    ``source`` declares in ``BOUND`` (a source that declares none is not checked); the
    message names the template (its path) and each missing or extra name."""
    declared = _declared_bindings(source)
    if declared is None:
        return
    missing = sorted(set(declared) - set(bindings))
    extra = sorted(set(bindings) - set(declared))
    if missing or extra:
        where = getattr(source, "path", f"the {label} source")
        raise ContractError(
            f"{where} declares BOUND = {declared}, but "
            + "; ".join(
                part
                for part in (
                    f"{', '.join(missing)} not bound" if missing else "",
                    f"{', '.join(extra)} bound but not declared" if extra else "",
                )
                if part
            )
        )


def compile_module(
    label: str, source: str, bindings: Mapping[str, object], description: str = ""
) -> types.ModuleType:
    """The module of generated ``source`` run with ``bindings`` in its namespace, its compiled
    functions cached on disk.

    Parameters
    ----------
    label : str
        A short name of what the module composes (``"rodas4-loop"``); the entry's folder
        starts with it.
    source : str
        Python source. Its compiled functions are declared ``@njit(**JIT_FLAGS)``; the
        loader binds ``JIT_FLAGS`` (softcell's kernel flags, cached on disk) and
        ``LEAN_JIT_FLAGS`` (the same without numba's reference counting, faster for a
        function that takes many arrays; such a function must not allocate one, nor
        inline a function that does).
    bindings : mapping of str to compiled function or scalar
        Global names the source uses: components' kernels, functions of other generated
        modules, constants (bool, int, float, str).
    description : str
        What it is for (the components), shown by ``softcell cache``.

    Returns
    -------
    module
        Loaded once per process and key. When a bound function cannot be identified (a
        closure, a function typed in a notebook), the module is compiled in memory instead,
        with a :class:`~softcell.plugin.blocks.CacheWarning` saying why.
    """
    check_bindings(label, source, bindings)
    try:
        key = entry_key(source, bindings)
    except NotCacheable as reason:
        warnings.warn(
            f"softcell: {label} is compiled in this process only, not cached on disk: {reason}",
            CacheWarning,
            stacklevel=2,
        )
        return _in_memory(label, source, bindings)
    store = module_store()
    if store is None:
        warnings.warn(
            f"softcell: {label} is compiled in this process only: no module store is set "
            "(softcell.settings.use_module_store)",
            CacheWarning,
            stacklevel=2,
        )
        return _in_memory(label, source, bindings)
    with _LOCK:
        where = store.location(label, key)
        if where in _LOADED:
            return _LOADED[where]
        try:
            filename = store.place(label, key, source, description)
        except (OSError, SoftcellError) as error:
            warnings.warn(
                f"softcell: cannot write the compiled-model cache at "
                f"{Path(where).parent.parent} ({getattr(error, 'strerror', None) or error}); "
                f"{label} is compiled in this process only (set SOFTCELL_CACHE_DIR to a "
                "writable folder)",
                CacheWarning,
                stacklevel=2,
            )
            return _in_memory(label, source, bindings)
        name = f"{_PARENT}.{label.replace('-', '_')}_{key[:20]}"
        module = _execute(name, filename, source, bindings, _CACHED)
        for value in vars(module).values():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name:
                _KEYS[id(value)] = key
        _LOADED[where] = module
        return module


def compiled_function(
    label: str, source: str, name: str, bindings: Mapping[str, object], description: str = ""
) -> Callable[..., object]:
    """The compiled function ``name`` of :func:`compile_module`'s module."""
    return getattr(compile_module(label, source, bindings, description), name)


def loaded_count() -> int:
    """How many cache entries this process has loaded so far: a mark for
    :func:`first_call_compiles`."""
    return len(_LOADED)


def first_call_compiles(since: int = 0) -> bool:
    """Whether the modules loaded by this process after mark ``since`` (see
    :func:`loaded_count`) still have to be compiled: numba keeps no index of the functions of
    the last of them on disk. The last one loaded is the outermost (a model's loop is
    composed after, and keyed by, the functions it calls), and numba's cache of it holds the
    machine code of everything it calls; a combination made but never called (an unused
    sum of partials, say) has no index and does not count. False when nothing was loaded."""
    with _LOCK:
        places = list(_LOADED)[since:]
    return bool(places) and not any((Path(places[-1]).parent / "__pycache__").glob("*.nbi"))
