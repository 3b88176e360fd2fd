"""The compiled model of one parameter point: the chosen components composed into one.

The energy terms' kernels are composed, by generated source, into one compiled function that
sums their partial derivatives; an integrator compiles that, the spectral force assembly and
the drive kernel into one stepper. The registry is consulted here, at set-up only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from softcell.components.contracts import (
    FrictionLaw,
    Integrator,
    Model,
    check_kernels,
)
from softcell.components.registry import Registry
from softcell.engine.compose import compose_partials
from softcell.engine.diagnose import probe_components
from softcell.model.parameters import Parameters


def build_model(
    params: Parameters,
    energy_terms: Sequence[str],
    protocol: str,
    membrane: bool = True,
    friction_law: str = "viscous",
    *,
    registry: Registry,
    pair_terms: Sequence[str] = (),
    bot_interactions: Sequence[str] = (),
) -> Model:
    """Instantiate the named components for ``params`` and compile their composition.

    Parameters
    ----------
    params : Parameters
        A validated parameter point (including the components' own parameters).
    energy_terms : sequence of str
        Names of registered energy terms.
    protocol : str
        Name of a registered driving protocol.
    membrane : bool
        False for a free bot: no membrane; of ``energy_terms`` only those acting on the bot
        alone are kept (the arena's walls).
    friction_law : str
        Name of a registered friction law (``viscous``, the paper's, by default).
    registry : Registry
        Where the names are looked up (``default_registry()``: built-ins and installed
        plugins).
    pair_terms : sequence of str
        Names of registered pair terms, for an assembly of cells (none for one cell).
    bot_interactions : sequence of str
        Names of registered bot interactions, for several bots in one ring (none for one).

    Returns
    -------
    Model
        The components instantiated for ``params`` and their composition, compiled.

    Raises
    ------
    ContractError
        When a component's kernel does not compile for its contract's signature, or writes
        a non-finite value at an initial state (naming origin, component, kernel, quantity).
    """
    terms = [registry.get("energy_term", n)(params) for n in energy_terms]
    if not membrane:
        terms = [t for t in terms if t.has_bot_energy]
    drive = registry.get("driving_protocol", protocol)(params)
    friction: FrictionLaw = registry.get("friction_law", friction_law)(params)
    pairs = [registry.get("pair_term", n)(params) for n in pair_terms]
    interactions = [registry.get("bot_interaction", n)(params) for n in bot_interactions]
    everything = (*terms, drive, friction, *pairs, *interactions)
    origins = {f"{c.kind} {c.name}": registry.origin(c.kind, c.name) for c in everything}
    for component in everything:
        check_kernels(component, origins[f"{component.kind} {component.name}"])
    kernels = [t.partials_kernel() for t in terms]
    coefficients = tuple(np.ascontiguousarray(t.coefficients()) for t in terms)
    if not coefficients:
        coefficients = (np.zeros(1),)
    l0 = params.membrane_length
    model = Model(
        params=params,
        terms=terms,
        protocol=drive,
        partials=compose_partials(kernels),
        coefficients=coefficients,
        drive=drive.drive_kernel(),
        drive_coefficients=np.ascontiguousarray(drive.coefficients()),
        context=np.array([l0, float(params.bot_semi_major), float(params.bot_semi_minor)]),
        membrane_mobility=2 * math.pi / (float(params.membrane_friction) * l0),
        bot_mobility=np.array(
            [
                1 / float(params.bot_friction),
                1 / float(params.bot_friction),
                1 / float(params.bot_rotational_friction),
            ]
        ),
        nodes=int(params.nodes),
        cutoff=int(params.cutoff),
        friction=friction,
        friction_coefficients=np.ascontiguousarray(friction.coefficients()),
        force_scale=2 * math.pi / l0,
        membrane=membrane,
        names={
            "energy_terms": [t.name for t in terms],
            "driving_protocol": protocol,
            "friction_law": friction_law,
        },
        origins=origins,
        pair_terms=pairs,
        event=drive.event_kernel(),
        bot_interactions=interactions,
    )
    probe_components(model)  # a kernel writing NaN is named here, before anything steps
    return model


def build_integrator(name: str, params: Parameters, registry: Registry) -> Integrator:
    """Instantiate the integrator ``name`` of ``registry`` (its ``check`` runs on
    ``params``; values in the units of ``softcell params``)."""
    return registry.get("integrator", name)(params)
