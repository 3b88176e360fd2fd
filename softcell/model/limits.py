"""What a run may ask for: limits set by this machine's memory and by float64.

:func:`check_run` is called on every parameter point before anything is computed: a request
that cannot fit (``duration = 1e12`` s records 1e13 samples; ``nodes = 2**30`` needs
hundreds of GiB per realization) is refused with the parameter, its value, the largest value
that fits and why, rather than crashing after minutes. :func:`check_seed` bounds the root seed
by what a file can store.
"""

from __future__ import annotations

import math
import os

from softcell.errors import ParameterError, SoftcellError

#: A realization may use at most this fraction of the machine's memory (the rest is for the
#: other worker, the analysis and the system).
MEMORY_FRACTION = 0.5
#: Copies of a stored sample held at once (the record, the Dataset, the writer's buffers).
#: With the modes and pose this estimates 3,800 B per sample at 64 stored nodes, against
#: 3,000 B measured (peak memory of 1e4 and 1e5 samples, rodas4, R = 8 cm).
SAMPLE_OVERHEAD = 3
#: Bytes per membrane collocation point an integrator holds: measured 98 (explicit_euler)
#: and 145 (rodas4) from the peak memory at 2**14 and 2**18 nodes; rounded up.
BYTES_PER_NODE = 256
#: Largest root seed: the seed is stored as an unsigned 64-bit attribute.
MAX_SEED = 2**64 - 1
#: Positions of size R carry a rounding error R * eps; the contact length lambda must stay
#: this many times larger (otherwise the contact force is evaluated from rounding noise).
CONTACT_RESOLUTION = 1e4


def machine_memory() -> int:
    """The memory this process may use (bytes): the machine's physical memory, or less where
    the process's address-space limit (``ulimit -v``) or its control group's limit (a batch
    job's, a container's) says so."""
    try:
        found = [int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))]
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        found = [8 << 30]
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft != resource.RLIM_INFINITY and soft > 0:
            found.append(int(soft))
    except (ImportError, OSError, ValueError):  # pragma: no cover - not POSIX
        pass
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = open(path, encoding="ascii").read().strip()  # noqa: SIM115
        except OSError:
            continue
        if text.isdigit() and 0 < int(text) < found[0]:
            found.append(int(text))
    return min(found)


def human_bytes(n: float) -> str:
    """A byte count with a binary unit, to 3 significant digits (``"23.5 GiB"``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} B"  # pragma: no cover


def sample_count(params) -> int:
    """Samples of one realization's record (the grid of ``engine.sample_times``), without
    building it."""
    duration, early = float(params.duration), float(params.sample_every)
    late, switch = float(params.sample_every_late), float(params.sample_switch)
    n = math.floor(min(switch, duration) / early * (1 + 1e-12)) + 1
    if switch < duration:
        n = math.ceil(switch / early) + math.floor((duration - switch) / late * (1 + 1e-12)) + 1
    return int(n)


def fine_count(params) -> int:
    """Samples of one realization's fine body record (``engine.fine_times``)."""
    return int(math.floor(float(params.duration) / float(params.sample_every) * (1 + 1e-12))) + 1


#: Bytes of one sample of the fine body record in a file: five float64 (cell centre, bot
#: pose) and the int8 phase.
FINE_SAMPLE_BYTES = 5 * 8 + 1


def sample_bytes(params) -> int:
    """Bytes of one stored sample in a simulation file (float64 membrane points, centre,
    bot pose and phase), before compression, which gains little on these data."""
    return 8 * (2 * int(params.stored_nodes) + 6) + 1


def file_bytes(params) -> int:
    """Expected size (bytes) of one realization's simulation file."""
    return (
        sample_count(params) * sample_bytes(params)
        + fine_count(params) * FINE_SAMPLE_BYTES
        + 64 * 1024
    )


def realization_bytes(params) -> dict[str, float]:
    """Memory (bytes) one realization needs, by the parameter that drives each part."""
    cutoff = int(params.cutoff)
    unknowns = 2 * (2 * cutoff + 1) + 3
    per_sample = 16 * (2 * cutoff + 1) + 40 + SAMPLE_OVERHEAD * sample_bytes(params)
    phases = float(params.duration) / float(params.phase_min) + 2
    return {
        "nodes": float(params.nodes) * BYTES_PER_NODE,
        "cutoff": 8.0 * unknowns**2 * 8,  # rodas4's Jacobian, LU and stage matrices
        "duration": sample_count(params) * per_sample
        + fine_count(params) * (40 + SAMPLE_OVERHEAD * FINE_SAMPLE_BYTES)
        + 17 * phases,
    }


def _stored_nodes_to_blame(params) -> bool:
    """Whether the stored points, rather than the duration, are the larger multiple of their
    default (the samples' memory grows as the product of the two)."""
    stored = float(params.stored_nodes) / float(params.specs["stored_nodes"].default)
    typical = 900.0 if float(params.radius) < 10.0 else 1800.0  # the derived default
    return stored > float(params.duration) / typical


def check_run(params, memory: int | None = None) -> None:
    """Raise :class:`ParameterError` unless one realization of ``params`` fits in memory.

    The message names the parameter whose share dominates, the largest value of it that
    fits with the others unchanged, and the memory involved.
    """
    memory = machine_memory() if memory is None else memory
    budget = MEMORY_FRACTION * memory
    parts = realization_bytes(params)
    total = sum(parts.values())
    if total <= budget:
        return
    name = max(parts, key=parts.get)
    room = budget - (total - parts[name])
    if name == "duration" and _stored_nodes_to_blame(params):
        name = "stored_nodes"  # the samples' size, not their number, is out of the ordinary
    spec = params.specs[name]
    value = float(params[name])
    if name in ("duration", "stored_nodes"):  # the samples' memory grows as each of them
        largest = value * max(room, 0.0) / parts["duration"]
    elif name == "cutoff":
        largest = value * math.sqrt(max(room, 0.0) / parts[name])
    else:
        largest = 2 ** math.floor(math.log2(max(room / BYTES_PER_NODE, 1.0)))
    unit = "" if spec.unit == "1" else f" {spec.unit}"
    shown = f"{int(largest)}" if spec.kind is int else f"{largest:.3g}"
    raise ParameterError(
        name,
        params[name],
        f"must be <= {shown}{unit}: one realization "
        f"would need {human_bytes(total)} of memory, more than "
        f"{MEMORY_FRACTION:.0%} of this machine's {human_bytes(memory)}",
        spec.unit,
    )


def max_radius(contact_length: float) -> float:
    """Largest radius (cm) at which float64 positions resolve the contact length."""
    return contact_length / (CONTACT_RESOLUTION * 2.0**-52)


#: Local worker processes per core, at most: more only share the cores and the memory.
WORKERS_PER_CORE = 4


def cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def check_worker_count(workers: object, name: str = "workers") -> int:
    """``workers`` local worker processes, checked: an integer from 1 to
    :data:`WORKERS_PER_CORE` per core of this machine.

    Raises
    ------
    SoftcellError
        One line naming the value (as ``name``) and the bound.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise SoftcellError(f"{name} = {workers!r} is not allowed: must be an integer >= 1")
    most = WORKERS_PER_CORE * cores()
    if workers > most:
        raise SoftcellError(
            f"{name} = {workers} is not allowed: this machine has {cores()} core(s), so at "
            f"most {most} local workers ({WORKERS_PER_CORE} per core); for more, run on a "
            "dask.distributed cluster (--scheduler ADDRESS)"
        )
    return workers


def check_realizations(realizations: object) -> int:
    """The realizations per point as an int >= 1, or a one-line error."""
    if isinstance(realizations, bool) or not isinstance(realizations, int) or realizations < 1:
        raise SoftcellError(
            f"realizations = {realizations!r} is not allowed: must be an integer >= 1"
        )
    return realizations


def check_seed(seed: object) -> int:
    """The root seed as an int in 0 .. 2**64 - 1, or a one-line error."""
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        raise SoftcellError(
            f"seed = {seed!r} is not allowed: must be an integer between 0 and "
            f"2**64 - 1 = {MAX_SEED} (it is stored in every file)"
        )
    return seed


def check_assembly_memory(params, cells: int, memory: int | None = None) -> None:
    """Raise :class:`ParameterError` naming ``cells`` unless one realization of an assembly
    of ``cells`` cells of ``params`` fits in memory (each cell's record is one cell's)."""
    memory = machine_memory() if memory is None else memory
    budget = MEMORY_FRACTION * memory
    one = sum(realization_bytes(params).values())
    if one * cells <= budget:
        return
    raise ParameterError(
        "cells",
        cells,
        f"must be <= {int(budget // one)}: one realization would need "
        f"{human_bytes(one * cells)} of memory, more than {MEMORY_FRACTION:.0%} of "
        f"{human_bytes(memory)}",
        "1",
    )
