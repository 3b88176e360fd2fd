"""Many cells in one plane: the outer loop of an assembly's realization.

Between two samples only cells in contact are coupled. At each sample the cells are split
into groups (:func:`~softcell.model.assembly.contact_groups` over their bounding circles, with
a margin larger than a sample's displacement); a cell alone is stepped by the integrator as a
single cell is (so an assembly of one cell is the single-cell run, to the bit), a group by the
integrator's group loop (its members and their membrane-membrane contact stepped together,
landing on every member's switches). After the interval the groups are formed again without
the margin: if two cells of different groups came within reach, the interval is redone with
their groups merged. The cost of a sample is then one step of each group, which grows
linearly with the number of cells at a fixed density, and M independent drives never force
every cell onto every switch.

Every length is in cm, every time in s.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from softcell.components.contracts import Schedule, Stepper
from softcell.engine.cell import SAMPLES_PER_CALL, Checkpoint, SampleGrid, Saved
from softcell.engine.interrupt import received, shielded
from softcell.engine.model import Model
from softcell.engine.state import (
    check_state,
    equilibrium_radius,
    fine_times,
    initial_state,
    phase_at,
    sample_times,
    sampling_plan,
)
from softcell.errors import Interrupted, ParameterError
from softcell.model.assembly import Assembly, Domain, contact_groups, place_cells
from softcell.settings import CHECKPOINT_EVERY

#: Extra reach (cm) of the groups formed before an interval, besides the contact's cut-off
#: and twice the free bot's displacement in one interval.
GROUP_MARGIN = 0.1

#: Samples per chunk of an assembly of more than one cell (see :func:`run_assembly`).
CHUNK = 10


def cell_rngs(seed: int, point: int, realization: int, cells: int) -> list[np.random.Generator]:
    """One Generator per cell: cell 0's is the single-cell stream of this realization,
    SeedSequence(seed, spawn_key=(point, realization)); cell i > 0 draws from
    SeedSequence(seed, spawn_key=(point, realization, i))."""
    keys = [(point, realization)] + [(point, realization, i) for i in range(1, cells)]
    return [
        np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=k)))
        for k in keys
    ]


def placement_rng(seed: int, point: int, realization: int) -> np.random.Generator:
    """The stream that places the cells (``random`` placement):
    SeedSequence(seed, spawn_key=(point, realization, 0)), distinct from every cell's."""
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(point, realization, 0)))
    )


def starting_centres(
    params, assembly: Assembly, seed: int, point: int, realization: int, reach: float
) -> np.ndarray:
    """Where the cells of one realization start (float64[M, 2], cm): rings of the
    equilibrium radius placed by :func:`~softcell.model.assembly.place_cells` (the
    ``random`` placement draws from :func:`placement_rng`), clear of the obstacles;
    ``reach`` (cm) is the pair terms' (a periodic box must exceed twice 2 R + reach).

    Raises
    ------
    SoftcellError
        When they cannot be placed (naming count, radius, gap, box and area fraction);
    ParameterError
        When a periodic box is too small for the rings to meet only one image of another.
    """
    radius = equilibrium_radius(params)
    obstacles = str(params.get("obstacles", "") or "")
    centres = place_cells(
        assembly.cells,
        radius,
        assembly.domain,
        placement_rng(seed, point, realization),
        placement=assembly.placement,
        gap=assembly.gap,
        obstacles=obstacles,
    )
    contact_groups(centres, radius, reach, assembly.domain)  # a periodic box's size
    return centres


@dataclass
class CrowdRecord:
    """What an assembly's realization produced: the membranes at ``times`` and the bodies'
    fine record at ``fine_times``, one column per cell."""

    times: np.ndarray  # float64[T], s
    modes: np.ndarray  # complex128[T, M, 2 Lc + 1], cm
    pose: np.ndarray  # float64[T, M, 3]: x, y (cm), heading (rad)
    phase: np.ndarray  # int8[T, M]
    fine_times: np.ndarray  # float64[F], s
    fine_center: np.ndarray  # complex128[F, M]: g_0, cm
    fine_pose: np.ndarray  # float64[F, M, 3]
    fine_phase: np.ndarray  # int8[F, M]
    states: list[dict[str, np.ndarray]] = field(default_factory=list)
    statistics: dict[str, int] = field(default_factory=dict)


def start_cells(
    model: Model,
    stepper: Stepper,
    centres: np.ndarray,
    rngs: list[np.random.Generator],
) -> tuple[list[dict[str, np.ndarray]], list[Schedule]]:
    """Each cell's starting state: the single-cell start (heading and schedule drawn from its
    own stream, the membrane at rest around the bot) moved to its centre (cm)."""
    states, schedules = [], []
    for centre, rng in zip(np.asarray(centres, dtype=np.float64), rngs, strict=True):
        modes, pose, schedule = initial_state(model, rng)
        modes[model.cutoff] += complex(centre[0], centre[1])
        pose[:2] += centre
        states.append(stepper.start(modes, pose, schedule))
        schedules.append(schedule)
    return states, schedules


def bounding_circles(states: list[dict[str, np.ndarray]], cutoff: int):
    """Centres (float64[M, 2], cm: g_0) and radii (float64[M], cm: sum over k != 0 of |g_k|,
    which bounds |z - g_0| everywhere) of the cells' membranes."""
    modes = np.array([s["modes"] for s in states])
    centres = np.stack([modes[:, cutoff].real, modes[:, cutoff].imag], axis=1)
    radii = np.abs(modes).sum(axis=1) - np.abs(modes[:, cutoff])
    return centres, radii


#: Up to this many cells, groups are found from all pairs (numpy) rather than a k-d tree
#: (whose set-up costs more below it).
DIRECT_GROUPS = 96


def _direct_groups(centres, radii, reach, domain: Domain) -> np.ndarray:
    """:func:`~softcell.model.assembly.contact_groups` from all pairs, for a few cells."""
    d = domain.displacement(centres[:, None, :], centres[None, :, :])
    close = np.hypot(d[..., 0], d[..., 1]) < radii[:, None] + radii[None, :] + reach
    parent = list(range(len(centres)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, j in zip(*np.nonzero(np.triu(close, 1)), strict=True):
        a, b = root(int(i)), root(int(j))
        if a != b:
            parent[max(a, b)] = min(a, b)
    roots = np.array([root(i) for i in range(len(centres))])
    _, labels = np.unique(roots, return_inverse=True)
    return labels.astype(np.int64)


def _merged(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The groups of cells linked by either labelling (labels numbered as contact_groups)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = first.size
    leads = []
    for labels in (first, second):
        _, lead = np.unique(labels, return_index=True)
        leads.append(lead[labels])
    i = np.arange(m)
    graph = coo_matrix(
        (np.ones(2 * m), (np.concatenate([i, i]), np.concatenate(leads))), shape=(m, m)
    )
    _, labels = connected_components(graph, directed=False)
    _, lead = np.unique(labels, return_index=True)
    return np.argsort(np.argsort(lead))[labels]


def _refines(after: np.ndarray, before: np.ndarray) -> bool:
    """True when every group of ``after`` lies within one group of ``before``."""
    for label in np.unique(after):
        if np.unique(before[after == label]).size > 1:
            return False
    return True


def _shifts(centres: np.ndarray, members: np.ndarray, domain: Domain) -> np.ndarray:
    """float64[G, G, 2]: the image shift (cm) of member d's points seen from member c."""
    c = centres[members]
    direct = c[None, :, :] - c[:, None, :]
    return domain.displacement(np.zeros_like(direct), direct) - direct


class _Crowd:
    """The cells' states and schedules, and how to advance them one interval; with
    ``threads`` > 1, a thread pool steps independent groups at once, each thread with its own
    twin of the stepper (:meth:`close` ends it)."""

    def __init__(self, model, stepper, domain, states, schedules, threads=1):
        if not hasattr(stepper, "advance_cells"):
            raise ParameterError(
                "integrator",
                type(stepper).__name__,
                "must step groups of cells (rodas4) for an assembly of more than one cell",
                "1",
            )
        self.model, self.stepper, self.domain = model, stepper, domain
        self.states, self.schedules = states, schedules
        self.steppers = [stepper] + [stepper.twin() for _ in range(threads - 1)]
        self.pool = ThreadPoolExecutor(threads - 1, "softcell-cells") if threads > 1 else None
        self.cutoff = model.pair_reach
        self.speed = float(model.params.drive_force) / float(model.params.bot_friction)
        self.together: dict[int, tuple[int, ...]] = {}  # each cell's group last interval
        self.redone = 0
        self.grouped_intervals = 0
        self.free_chunks = 0

    def groups(self, reach: float, members: np.ndarray) -> np.ndarray:
        """Group labels of the cells ``members`` (indices), -1 for the others."""
        labels = np.full(len(self.states), -1, dtype=np.int64)
        if members.size == 1:
            labels[members] = 0
            return labels
        centres, radii = bounding_circles([self.states[c] for c in members], self.model.cutoff)
        if members.size > DIRECT_GROUPS:
            labels[members] = contact_groups(centres, radii, reach, self.domain)
        else:
            labels[members] = _direct_groups(centres, radii, reach, self.domain)
        return labels

    def free(self, span: float) -> np.ndarray:
        """The cells that no other can reach within ``span`` (s): their bounding circles
        (each may move and grow by twice the free bot's displacement) stay farther apart
        than the cut-off."""
        cells = len(self.states)
        if cells == 1:
            return np.ones(1, dtype=bool)
        centres, radii = bounding_circles(self.states, self.model.cutoff)
        d = self.domain.displacement(centres[:, None, :], centres[None, :, :])
        gap = np.hypot(d[..., 0], d[..., 1]) - radii[:, None] - radii[None, :]
        np.fill_diagonal(gap, np.inf)
        return gap.min(axis=1) > self.cutoff + GROUP_MARGIN + 4 * self.speed * span

    def chunk(self, grid: _Samples, first: int, stop: int) -> None:
        """Advance every cell over grid samples ``first`` to ``stop - 1`` and record them."""
        times = grid.times
        free = self.free(float(times[stop - 1] - times[first - 1]))
        rows = slice(first, stop)
        alone = [(1, (int(c),), None, False) for c in np.flatnonzero(free)]
        for (_, (c,), _, _), (modes, pose) in zip(
            alone, self._run(alone, times[rows]), strict=True
        ):
            grid.keep_cell(rows, c, modes, pose)
            self.free_chunks += 1
        self.together = {}  # groups start afresh in each chunk (a checkpoint's boundary)
        busy = np.flatnonzero(~free)
        if busy.size == 0:
            return
        for i in range(first, stop):
            self.advance(busy, float(times[i]), float(times[i] - times[i - 1]))
            grid.keep_row(
                i,
                busy,
                np.array([self.states[c]["modes"] for c in busy]),
                np.array([self.states[c]["pose"] for c in busy]),
            )

    def advance(self, members: np.ndarray, t_end: float, dt: float) -> None:
        """Advance the cells ``members`` to ``t_end`` (s), redoing the interval if groups
        met."""
        saved = {int(c): {k: v.copy() for k, v in self.states[c].items()} for c in members}
        labels = self.groups(self.cutoff + 2 * self.speed * dt + GROUP_MARGIN, members)
        while True:
            self._step(labels, t_end)
            after = self.groups(self.cutoff, members)
            if _refines(after[members], labels[members]):
                return
            self.redone += 1
            labels[members] = _merged(labels[members], after[members])
            for c, kept in saved.items():
                for k, v in kept.items():
                    self.states[c][k][...] = v

    def _step(self, labels: np.ndarray, t_end: float) -> None:
        centres, _ = bounding_circles(self.states, self.model.cutoff)
        together: dict[int, tuple[int, ...]] = {}
        jobs = []
        for label in np.unique(labels[labels >= 0]):
            members = np.flatnonzero(labels == label)
            key = tuple(int(c) for c in members)
            for c in key:
                together[c] = key
            if members.size == 1:
                jobs.append((1, key, None, False))
                continue
            self.grouped_intervals += 1
            shifts = _shifts(centres, members, self.domain)
            jobs.append((members.size, key, shifts, any(self.together.get(c) != key for c in key)))
        self._run(jobs, np.array([t_end]))
        self.together = together

    def _run(self, jobs: list[tuple], times: np.ndarray) -> list:
        """Do ``jobs`` (size, cells, shifts, rewind): a cell alone sampled at ``times`` (s),
        a group advanced to ``times[-1]``; returns each job's samples (a group's: None). With
        a pool, every thread (the calling one too) takes the next job not yet taken, largest
        group first, until none is left; each job touches its own cells' states only, so the
        states are the same whichever thread did it."""
        if self.pool is None or len(jobs) < 2:
            return [self._job(self.stepper, job, times) for job in jobs]
        order = sorted(range(len(jobs)), key=lambda i: -jobs[i][0])
        taken = itertools.count()  # next() is atomic under the GIL
        results: list = [None] * len(jobs)

        def work(stepper) -> None:
            for n in taken:
                if n >= len(order):
                    return
                results[order[n]] = self._job(stepper, jobs[order[n]], times)

        others = [self.pool.submit(work, s) for s in self.steppers[1:]]
        try:
            work(self.stepper)
        finally:
            for other in others:  # every thread done before the states are read or saved
                other.result()
        return results

    def close(self) -> None:
        """End the thread pool, if any."""
        if self.pool is not None:
            self.pool.shutdown()

    def _job(self, stepper, job: tuple, times: np.ndarray):
        size, key, shifts, rewind = job
        if size == 1:
            c = key[0]
            return stepper.sample(self.states[c], self.schedules[c], times)
        stepper.advance_cells(
            [self.states[c] for c in key],
            [self.schedules[c] for c in key],
            shifts,
            float(times[-1]),
            rewind=rewind,
        )
        return None


class _Samples(SampleGrid):
    """An assembly's record on its sampling grid: a cell axis after the sample axis, filled
    cell by cell; a checkpoint stacks every cell's state."""

    def __init__(self, times, membrane, fine, cells: int, cutoff: int):
        super().__init__(
            times,
            membrane,
            fine,
            np.empty((membrane.size, cells, 2 * cutoff + 1), dtype=np.complex128),
            np.empty((times.size, cells, 3)),
            np.empty((times.size, cells), dtype=np.complex128),
        )
        self.cutoff = cutoff
        self.slot = np.full(times.size, -1)
        self.slot[membrane] = np.arange(membrane.size)

    def keep_cell(self, rows: slice, cell: int, modes: np.ndarray, pose: np.ndarray) -> None:
        """Cell ``cell``'s samples of grid rows ``rows``: modes (K, m), pose (K, 3)."""
        self.pose[rows, cell] = pose
        self.center[rows, cell] = modes[:, self.cutoff]
        slots = self.slot[rows]
        kept = slots >= 0
        self.modes[slots[kept], cell] = modes[kept]

    def keep_row(self, row: int, cells: np.ndarray, modes: np.ndarray, pose: np.ndarray) -> None:
        """The cells ``cells``' samples of grid row ``row``: modes (C, m), pose (C, 3)."""
        self.pose[row, cells] = pose
        self.center[row, cells] = modes[:, self.cutoff]
        if self.slot[row] >= 0:
            self.modes[self.slot[row], cells] = modes

    def saved_cells(self, sample: int, states: list[dict[str, np.ndarray]]) -> Saved:
        """What a checkpoint keeps at grid sample ``sample`` (every cell's state stacked)."""
        return self.saved(sample, {k: np.stack([s[k] for s in states]) for k in states[0]})

    def restore_cells(self, saved: Saved, states: list[dict[str, np.ndarray]]) -> int:
        self.restore(saved)
        for c, state in enumerate(states):
            for k, v in saved.state.items():
                state[k][...] = v[c]
        return saved.next_sample


def _copies(states: list[dict[str, np.ndarray]]) -> list[dict[str, np.ndarray]]:
    return [{k: v.copy() for k, v in s.items()} for s in states]


def run_assembly(
    model: Model,
    stepper: Stepper,
    domain: Domain,
    centres: np.ndarray,
    rngs: list[np.random.Generator],
    *,
    label: object = 0,
    checkpoint: Checkpoint | None = None,
    checkpoint_every: float = CHECKPOINT_EVERY,
    progress: Callable[[float], None] | None = None,
    stop: Callable[[], bool] | None = None,
    threads: int = 1,
) -> CrowdRecord:
    """Integrate one realization of an assembly: cell i starts at ``centres[i]`` (cm) with
    the stream ``rngs[i]``; the membranes are sampled at
    :func:`~softcell.engine.state.sample_times`, the cells' centres and the bots' poses
    at :func:`~softcell.engine.state.fine_times`. Positions are never wrapped: in a
    periodic box they are continuous (unwrapped) trajectories.

    The samples go by chunks (:data:`CHUNK` samples; one cell: SAMPLES_PER_CALL, as a single
    cell's run): a cell far enough from every other that neither can reach the other within
    the chunk (:data:`GROUP_MARGIN` and the cut-off beyond four free-bot displacements) is
    stepped alone through it; the others sample by sample, in groups. Every cell is at the
    chunk's end before the next starts: that is where checkpoints are saved.

    Parameters
    ----------
    checkpoint : Checkpoint, optional
        Saved every ``checkpoint_every`` wall seconds (s) at the end of a chunk, and when
        interrupted; resumed from when it holds progress (to the same bytes).
    progress : callable, optional
        Called with the simulated seconds (s) advanced since its last call.
    stop : callable, optional
        Asked between chunks; True stops the run as Ctrl-C does.
    threads : int
        Threads that step independent groups (and cells alone) at once, each with a twin of
        the stepper (its ``twin()``; an integrator without one steps on one thread). The
        record is the same to the bit whatever their number.

    Raises
    ------
    Interrupted
        On Ctrl-C or ``stop``, after saving the checkpoint; its message says where.
    SimulationError
        When a step fails or a cell's state is not finite (naming the cell).
    """
    times, membrane, fine = sampling_plan(model.params)
    states, schedules = start_cells(model, stepper, centres, rngs)
    cells = len(states)
    crowd = _Crowd(model, stepper, domain, states, schedules, _threads(threads, cells, stepper))
    grid = _Samples(times, membrane, fine, cells, model.cutoff)
    first = _start(model, states, grid, checkpoint, label, progress)
    chunk = SAMPLES_PER_CALL if cells == 1 else CHUNK
    done, done_states, last_save = first, _copies(states), time.monotonic()
    # A group's LU (G x 69 unknowns) is large enough for OpenBLAS to start threads, which
    # spin between calls and take the other core from a second worker: one thread here.
    limits = threadpool_limits(limits=1, user_api="blas")
    try:
        for i in range(first, times.size, chunk):
            j = min(i + chunk, times.size)
            crowd.chunk(grid, i, j)
            for c, s in enumerate(states):
                check_state(s, model, f"{label}, cell {c}")
            done, done_states = j, _copies(states)
            if progress:
                progress(float(times[j - 1] - times[i - 1]))
            if checkpoint is not None and time.monotonic() - last_save > checkpoint_every:
                checkpoint.save(grid.saved_cells(j, states))
                last_save = time.monotonic()
            if received() or (stop is not None and stop()):
                raise KeyboardInterrupt
    except KeyboardInterrupt:
        if checkpoint is not None:
            with shielded():
                checkpoint.save(grid.saved_cells(done, done_states))
        raise Interrupted(
            f"interrupted at t = {times[done - 1]:.2f} s of {label}"
            + ("; rerun the same command to resume" if checkpoint else "")
        ) from None
    finally:
        limits.restore_original_limits()
        crowd.close()
    return _record(model, crowd, grid, fine)


def _threads(threads: int, cells: int, stepper: Stepper) -> int:
    """The threads an assembly's realization uses: ``threads`` (checked), one for one cell or
    an integrator that cannot make a twin of its stepper."""
    if isinstance(threads, bool) or not isinstance(threads, int | np.integer) or threads < 1:
        raise ParameterError("threads", threads, "must be an integer >= 1", "1")
    if cells == 1 or not hasattr(stepper, "twin"):
        return 1
    return int(min(threads, cells))


def _start(model, states, grid: _Samples, checkpoint, label, progress) -> int:
    """Record the cells' starting states (checked), or restore the checkpoint's progress;
    returns the first grid sample still to compute."""
    saved = checkpoint.load() if checkpoint is not None else None
    if saved is None:
        for c, s in enumerate(states):
            check_state(s, model, f"{label}, cell {c}")
            grid.keep_cell(slice(0, 1), c, s["modes"][None], s["pose"][None])
        return 1
    first = grid.restore_cells(saved, states)
    if progress:
        progress(float(grid.times[first - 1]))
    return first


def _record(model, crowd: _Crowd, grid: _Samples, fine: np.ndarray) -> CrowdRecord:
    membrane_times, fine_times_ = sample_times(model.params), fine_times(model.params)
    schedules = crowd.schedules
    return CrowdRecord(
        membrane_times,
        grid.modes,
        grid.pose[grid.membrane],
        np.stack([phase_at(s, membrane_times) for s in schedules], axis=1),
        fine_times_,
        grid.center[fine],
        grid.pose[fine],
        np.stack([phase_at(s, fine_times_) for s in schedules], axis=1),
        crowd.states,
        {
            "redone_intervals": crowd.redone,
            "grouped_intervals": crowd.grouped_intervals,
            "free_chunks": crowd.free_chunks,
        },
    )


def membrane_record(params) -> str:
    """What an assembly's file keeps of the membranes, in words (its ``membrane_record``
    attribute): the sampling intervals (s), the switch time (s) and the stored points."""
    early, late = float(params.sample_every), float(params.sample_every_late)
    switch, duration = float(params.sample_switch), float(params.duration)
    nodes, modes = int(params.stored_nodes), 2 * int(params.cutoff) + 1
    if switch <= 0.0 or early == late:
        when = f"every {late if switch <= 0.0 else early:g} s"
    elif switch >= duration:
        when = f"every {early:g} s"
    else:
        when = f"every {early:g} s until {switch:g} s, then every {late:g} s"
    return (
        f"membranes {when} at {nodes} points (from {modes} Fourier modes); the cells' "
        f"centres and the bots' poses every {early:g} s (the fine record)"
    )


def crowd_dataset(
    record: CrowdRecord,
    model: Model,
    assembly: Assembly,
    centres: np.ndarray,
    *,
    realization: int,
    seed: int,
    components: dict[str, object],
    extra_attrs: dict[str, object] | None = None,
    scalar_coords: tuple[str, ...] = ("radius",),
):
    """The simulation Dataset of one realization of an assembly: the variables of one cell
    with a ``cell`` dim after the time dim, the domain (``domain_box``, cm, with its
    ``boundary``) and the cells' starting centres (cm)."""
    from softcell.engine.kernels.spectral import resample
    from softcell.schema import simulation_dataset

    nodes = int(model.params.stored_nodes)
    times, cells = record.modes.shape[:2]
    extra_attrs = {**(extra_attrs or {}), "membrane_record": membrane_record(model.params)}
    mx, my = resample(record.modes.reshape(times * cells, -1), nodes)
    center = record.modes[:, :, model.cutoff]
    fine = {
        "fine_time": record.fine_times,
        "cell_x_fine": record.fine_center.real[None],
        "cell_y_fine": record.fine_center.imag[None],
        "bot_x_fine": record.fine_pose[None, :, :, 0],
        "bot_y_fine": record.fine_pose[None, :, :, 1],
        "bot_angle_fine": record.fine_pose[None, :, :, 2],
        "bot_phase_fine": record.fine_phase[None],
    }
    return simulation_dataset(
        record.times,
        np.array([realization]),
        membrane_x=mx.reshape(1, times, cells, nodes),
        membrane_y=my.reshape(1, times, cells, nodes),
        cell_x=center.real[None],
        cell_y=center.imag[None],
        bot_x=record.pose[None, :, :, 0],
        bot_y=record.pose[None, :, :, 1],
        bot_angle=record.pose[None, :, :, 2],
        bot_phase=record.phase[None],
        parameters=model.params,
        seed=seed,
        components=components,
        extra_attrs=extra_attrs,
        scalar_coords=scalar_coords,
        fine=fine,
        domain={
            "box": np.nan if assembly.box is None else assembly.box,
            "boundary": assembly.boundary,
            "start_x": np.asarray(centres)[:, 0],
            "start_y": np.asarray(centres)[:, 1],
        },
    )
