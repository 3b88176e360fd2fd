"""Every extension point of softcell, in one module.

A plugin is a module (or object) with functions named after these hooks and marked with
:data:`softcell.plugin.hookimpl`. Each hook takes no arguments and returns a list of component
*classes*; softcell instantiates them later with a validated :class:`~softcell.Parameters`.

Hooks are called once, when the registry is built (the first time a component is looked up
by name, or ``softcell plugins`` runs). They are never called inside a time loop: components
hand compiled kernels to the engine instead. Built-in components are registered through the
same hooks as third-party ones (``softcell.builtins``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:
    from softcell.components.contracts import (
        BotInteraction,
        DrivingProtocol,
        EnergyTerm,
        FrictionLaw,
        Integrator,
        PairTerm,
        StopGoDetector,
    )

hookspec = pluggy.HookspecMarker("softcell")
hookimpl = pluggy.HookimplMarker("softcell")

# ---------------------------------------------------------------------------------------------
# The model: membrane energy, the bot's drive, time integration
# ---------------------------------------------------------------------------------------------


@hookspec
def softcell_energy_terms() -> list[type[EnergyTerm]]:
    """Membrane energy terms this plugin provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.EnergyTerm`. Each supplies an energy
        density per unit of the curve parameter xi (N cm, so that E = integral over xi in
        [0, 2 pi) is in N cm) and a compiled kernel for its pointwise partial derivatives
        P0 = de/dgamma (N), P1 = de/dgamma' (N), P2 = de/dgamma'' (N) at the collocation points,
        and, if it involves the bot, de/d(bot pose).

    Called once when the registry is built.
    """


@hookspec
def softcell_driving_protocols() -> list[type[DrivingProtocol]]:
    """Driving protocols (the bot's internal drive) this plugin provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.DrivingProtocol`. Each draws its whole
        phase schedule (start times in s, phase codes, per-phase data) from a
        :class:`numpy.random.Generator`, and supplies a compiled kernel that maps the phase and
        the bot's state (x, y in cm, heading in rad) to a drive force (N) and torque (N cm).

    Called once when the registry is built.
    """


@hookspec
def softcell_friction_laws() -> list[type[FrictionLaw]]:
    """Friction laws (how a membrane element moves under the force on it) this plugin
    provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.FrictionLaw`. Each supplies a compiled kernel
        mapping the force density at the membrane's collocation points (N cm^-1, per unit
        length) to their velocity (cm s^-1), and optionally its derivative
        (cm^2 N^-1 s^-1), for implicit integrators.

    Called once when the registry is built.
    """


@hookspec
def softcell_integrators() -> list[type[Integrator]]:
    """Time integrators this plugin provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.Integrator`. Each advances the coupled
        bot-membrane state (membrane Fourier modes in cm, bot position in cm, heading in rad)
        from one sample time (s) to the next.

    Called once when the registry is built.
    """


# ---------------------------------------------------------------------------------------------
# Analysis
# ---------------------------------------------------------------------------------------------


@hookspec
def softcell_stopgo_detectors() -> list[type[StopGoDetector]]:
    """Stop/go detectors this plugin provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.StopGoDetector`. Each labels every
        sample of a speed series (cm/s) as stop (0), go (1) or unknown (-1, where the speed
        is NaN).

    Called once when the registry is built.
    """


@hookspec
def softcell_pair_terms() -> list[type[PairTerm]]:
    """Interactions between the membranes of two cells of an assembly this plugin provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.PairTerm`. Each supplies an energy density
        e(rho) (N cm per unit xi) of a membrane point at signed distance rho (cm) from another
        cell's membrane, its first two derivatives (N, N cm^-1) in a compiled kernel, and
        the distance beyond which it vanishes (cm). An assembly chooses its terms by name
        (``pair_terms`` in ``[assembly]``, ``--pair-terms``; default ``repulsion``).

    Called once when the registry is built.
    """


@hookspec
def softcell_bot_interactions() -> list[type[BotInteraction]]:
    """Interactions between the bots of one ring (``--bots K`` > 1) this plugin provides.

    Returns
    -------
    list of type
        Subclasses of :class:`softcell.plugin.BotInteraction`. Each supplies a compiled
        kernel adding the generalized forces (N, N, N cm) on two bots from their poses (cm,
        cm, rad), and the distance between their centres (cm) beyond which it adds nothing.
        A run chooses them by name (``interactions`` in ``[bots]``, ``--bot-interactions``;
        default ``bot_repulsion``).

    Called once when the registry is built.
    """
