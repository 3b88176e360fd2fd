"""Several bots in one ring: their streams, their start and their record as a Dataset.

Bot 0 draws from the realization's single-bot stream, SeedSequence(seed, spawn_key=(point,
realization)), so its heading and schedule are those of a run of one bot; bot i > 0 draws
from spawn_key (point, realization, i), and the positions of a random placement from
(point, realization, 0). Each bot draws its heading, then its schedule, as one bot does. The
ring starts as the equilibrium circle centred on the origin. The loop is
:func:`~softcell.engine.cell.run_realization`'s, with the state and schedules made here.
"""

from __future__ import annotations

import numpy as np

from softcell.components.contracts import Schedule
from softcell.engine.groups import cell_rngs, placement_rng
from softcell.engine.model import Model
from softcell.engine.state import Record, circle_modes, equilibrium_radius
from softcell.model.bots import Bots, place_bots

__all__ = ["bot_rngs", "bots_dataset", "placement_rng", "start_bots"]


def bot_rngs(seed: int, point: int, realization: int, bots: int) -> list[np.random.Generator]:
    """One Generator per bot (see the module's docstring): bot 0's is the single-bot
    stream of this realization."""
    return cell_rngs(seed, point, realization, bots)


def start_bots(
    model: Model, bots: Bots, rngs: list[np.random.Generator], placement: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, list[Schedule]]:
    """The ring's starting modes (complex128[2 Lc + 1], cm), the bots' starting poses
    (float64[K, 3]: cm, cm, rad) and their schedules.

    Raises
    ------
    ParameterError
        When the bots do not fit in the ring (:func:`~softcell.model.bots.place_bots`).
    """
    params = model.params
    headings, schedules = [], []
    for rng in rngs:
        headings.append(model.protocol.initial_heading(rng))
        schedules.append(model.protocol.schedule(rng, float(params.duration)))
    radius = equilibrium_radius(params)
    a, b = float(params.bot_semi_major), float(params.bot_semi_minor)
    poses = place_bots(bots, radius, a, b, np.array(headings), placement)
    return circle_modes(radius, model.cutoff), poses, schedules


def bots_dataset(
    record: Record,
    model: Model,
    bots: Bots,
    start: np.ndarray,
    *,
    realization: int,
    seed: int,
    components: dict[str, object],
    extra_attrs: dict[str, object] | None = None,
    scalar_coords: tuple[str, ...] = ("radius",),
):
    """The simulation Dataset of one realization of K bots in one ring: the variables of one
    bot with a ``bot`` dim after their time dim ([1, T, K]), and the bots' starting poses
    (``bot_start_x``, ``bot_start_y``, ``bot_start_angle``; the settings in the attribute
    ``bots`` of the first)."""
    from softcell.engine.kernels.spectral import resample
    from softcell.schema import simulation_dataset

    k = bots.count
    pose = record.pose.reshape(record.pose.shape[0], k, 3)
    fine_pose = record.fine_pose.reshape(record.fine_pose.shape[0], k, 3)
    mx, my = resample(record.modes, int(model.params.stored_nodes))
    cell = record.modes[:, model.cutoff]
    fine = {
        "fine_time": record.fine_times,
        "cell_x_fine": record.fine_center.real[None],
        "cell_y_fine": record.fine_center.imag[None],
        "bot_x_fine": fine_pose[None, :, :, 0],
        "bot_y_fine": fine_pose[None, :, :, 1],
        "bot_angle_fine": fine_pose[None, :, :, 2],
        "bot_phase_fine": record.fine_phase[None],
    }
    return simulation_dataset(
        record.times,
        np.array([realization]),
        membrane_x=mx[None],
        membrane_y=my[None],
        cell_x=cell.real[None],
        cell_y=cell.imag[None],
        bot_x=pose[None, :, :, 0],
        bot_y=pose[None, :, :, 1],
        bot_angle=pose[None, :, :, 2],
        bot_phase=record.phase[None],
        parameters=model.params,
        seed=seed,
        components=components,
        extra_attrs=extra_attrs,
        scalar_coords=scalar_coords,
        fine=fine,
        bots={"start": start, "settings": bots.as_dict()},
    )
