"""Numerical settings in one place: numba flags, cut-offs, tolerances.

Kernels take their decorator options from here (``@njit(**JIT)``) rather than scattering
flags through the code.
"""

from __future__ import annotations

#: Options of every compiled kernel. ``fastmath`` stays off: the explicit reference must be
#: reproducible to the last bit, and checkpoints must resume to the same bytes.
#: (Read as ``softcell.settings.JIT``: taking it first has numba keep the cache files of
#: softcell's own functions in the module store's cache, see :func:`use_module_store`.)
_JIT: dict[str, object] = {"cache": True, "fastmath": False, "error_model": "numpy", "nogil": True}

#: Options of the kernels that take a compiled function as an argument (the generic Rosenbrock
#: stage, :mod:`softcell.engine.kernels.rosenbrock`): those of the kernels, but not cached on their
#: own; they are compiled into the generated modules that call them, which are.
JIT_COMPOSED: dict[str, object] = {**_JIT, "cache": False}

#: Membrane points farther than this many contact lengths lambda from the bot feel no contact
#: force (exp(-25) ~ 1.4e-11 of the force at contact).
CONTACT_CUTOFF_LENGTHS = 25.0

#: A run stops with an error when the membrane length departs from l0 by more than this
#: fraction (the model keeps it within ~0.1 %).
BLOWUP_LENGTH_FRACTION = 0.05

#: Points of the trapezoidal membrane length in that check (ample for a 5 % test).
BLOWUP_CHECK_POINTS = 64

#: Most safeguarded Newton iterations of the ellipse distance (each at least halves the bracket
#: when Newton misbehaves, so 200 reach rounding from any start).
ELLIPSE_ITERATIONS = 200

#: Wall seconds between checkpoints of a running realization (``--checkpoint-every``).
CHECKPOINT_EVERY = 60.0


def progress_bar_class():
    """tqdm's bar class for this session: a notebook's widget where Jupyter can draw one, the
    console's otherwise (without the warning tqdm gives when ipywidgets is missing)."""
    import warnings

    from tqdm import TqdmWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TqdmWarning)
        from tqdm.auto import tqdm
    return tqdm


#: The module whose ``DiskStore`` is the default module store (the compiled-model cache on
#: disk), imported when a composed model is first placed: importing softcell sets nothing.
DEFAULT_STORE = "softcell.io.model_cache"

_module_stores: list[object] = []  # empty: the default store, made on first use


def use_module_store(store: object) -> None:
    """Keep the composed models in ``store`` from now on: an object with
    ``place(label, key, source, description) -> str`` that stores a generated module's source
    and returns its path (see :class:`softcell.engine.compiled.ModuleStore`), and
    optionally ``cache_kernels()``, called once before the first kernel is compiled, to keep
    numba's cache files of softcell's own functions too; None compiles composed models in
    memory, in each process. By default the disk cache of :data:`DEFAULT_STORE` is used."""
    _module_stores[:] = [store]


def __getattr__(name: str) -> object:
    # ``JIT`` is handed out here so that the store may place numba's cache files of the
    # kernels before the first ``@njit(**JIT)`` picks where they go. ``LEAN_JIT``, the same
    # without numba's reference counting (its private ``_nrt`` option), is for the kernels of
    # the implicit step that never allocate: counting the references of every array argument
    # at every call was a twentieth of a step.
    if name in ("JIT", "LEAN_JIT"):
        store = module_store()
        if store is not None and hasattr(store, "cache_kernels"):
            store.cache_kernels()
        return _JIT if name == "JIT" else {**_JIT, "_nrt": False}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def module_store() -> object | None:
    """The store set by :func:`use_module_store`, else the default disk store (made on first
    use); None when composed models are compiled in memory, in each process."""
    if not _module_stores:
        import importlib

        _module_stores.append(importlib.import_module(DEFAULT_STORE).DiskStore())
    return _module_stores[0]
