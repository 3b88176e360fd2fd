"""The compiled model of one parameter point: the chosen components composed into one.

The energy terms' kernels are composed, by generated source, into one compiled function that
sums their partial derivatives; an integrator compiles that, the spectral force assembly and
the drive kernel into one stepper. The registry is consulted here, at set-up only.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from softcell.components.contracts import (
    DrivingProtocol,
    EnergyTerm,
    FrictionLaw,
    Integrator,
    PairTerm,
    check_kernels,
)
from softcell.components.registry import Registry
from softcell.engine.compose import compose_partials
from softcell.engine.diagnose import probe_components
from softcell.model.parameters import Parameters


@dataclass
class Model:
    """The compiled model of one parameter point: what an integrator composes into a stepper.

    Attributes
    ----------
    params : Parameters
    terms : list of EnergyTerm
        For a free bot (``membrane`` False), only the terms that act on the bot alone
        (:meth:`EnergyTerm.bot_kernel`; the arena's walls).
    protocol : DrivingProtocol
    partials : compiled function
        Sum of the terms' partials kernels (see ``compose_partials``).
    coefficients : tuple of float64 arrays
        One per term.
    drive : compiled function
        The protocol's drive kernel.
    drive_coefficients : ndarray
        float64: the protocol's coefficients, each in its declared unit.
    context : float64[3]
        l0 (cm), bot semi-major and semi-minor axes (cm).
    membrane_mobility : float
        2 pi / (gamma_mem l0) (cm^2 N^-1 s^-1 per unit xi): dg_k/dt = membrane_mobility f_hat_k.
    bot_mobility : float64[3]
        1/gamma_T, 1/gamma_T (cm N^-1 s^-1) and 1/gamma_R (N^-1 cm^-1 s^-1).
    nodes : int
        Collocation points N of the membrane.
    cutoff : int
        Fourier cutoff Lc: modes k = -Lc..Lc.
    membrane : bool
        False for a free bot (no membrane; see ``has_membrane``).
    friction : FrictionLaw
        The membrane's friction law. When it is
        not ``linear``, an integrator evaluates the force density
        f = (2 pi / l0) sum_k f_hat_k e^{i k xi} (N cm^-1) at M points (the smallest power of
        two >= 8 Lc, at most N: 128), applies the law's kernel there and moves the modes by the
        velocity's modes ``|k| <= Lc``.
    friction_coefficients : ndarray
        float64: the friction law's coefficients, each in its declared unit.
    force_scale : float
        2 pi / l0 (cm^-1), the factor above.
    names : dict
        The component names by kind, as files store them.
    origins : dict
        Where each component came from, by ``"<kind> <name>"`` (for errors that name it).
    pair_terms : list of PairTerm
        The pair terms between the membranes of an assembly's cells (none for one cell).
    event : callable or None
        The protocol's compiled event kernel (:meth:`DrivingProtocol.event_kernel`; its value
        in the unit the protocol chooses, >= 0 ends the phase), or None.
    """

    params: Parameters
    terms: list[EnergyTerm]
    protocol: DrivingProtocol
    partials: Callable[..., None]
    coefficients: tuple[np.ndarray, ...]
    drive: Callable[..., None]
    drive_coefficients: np.ndarray
    context: np.ndarray
    membrane_mobility: float
    bot_mobility: np.ndarray
    nodes: int
    cutoff: int
    membrane: bool = True
    friction: FrictionLaw | None = None
    friction_coefficients: np.ndarray = field(default_factory=lambda: np.zeros(1))
    force_scale: float = 1.0
    names: dict[str, object] = field(default_factory=dict)
    #: Where each component came from, by ``"<kind> <name>"`` (for errors that name it).
    origins: dict[str, str] = field(default_factory=dict)
    #: The pair terms between the membranes of an assembly's cells (none for one cell).
    pair_terms: list[PairTerm] = field(default_factory=list)
    #: The protocol's compiled event kernel, or None (:meth:`DrivingProtocol.event_kernel`).
    event: Callable[..., float] | None = None

    @property
    def pair_reach(self) -> float:
        """The distance (cm) within which the pair terms act: the largest reach."""
        return max((t.reach() for t in self.pair_terms), default=0.0)

    @property
    def has_membrane(self) -> bool:
        return self.membrane and bool(self.terms)

    @property
    def bot_terms(self) -> list[EnergyTerm]:
        """The terms with an energy of the bot alone (:meth:`EnergyTerm.bot_kernel`)."""
        return [t for t in self.terms if t.has_bot_energy]

    @property
    def reads_pose(self) -> bool:
        """True if any term's density depends on the bot's pose."""
        return any(t.reads_pose for t in self.terms)

    @property
    def couples_bot(self) -> bool:
        """Deprecated name of :attr:`reads_pose` (until softcell 0.4)."""
        import warnings

        warnings.warn(
            "Model.couples_bot was renamed Model.reads_pose in softcell 0.3",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.reads_pose

    @property
    def nonlinear_friction(self) -> bool:
        """True when the friction law is not the linear v = f / gamma_mem (integrators then
        apply the law's kernel)."""
        return self.has_membrane and self.friction is not None and not self.friction.linear


def build_model(
    params: Parameters,
    energy_terms: Sequence[str],
    protocol: str,
    membrane: bool = True,
    friction_law: str = "viscous",
    *,
    registry: Registry,
    pair_terms: Sequence[str] = (),
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
    everything = (*terms, drive, friction, *pairs)
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
    )
    probe_components(model)  # a kernel writing NaN is named here, before anything steps
    return model


def build_integrator(name: str, params: Parameters, registry: Registry) -> Integrator:
    """Instantiate the integrator ``name`` of ``registry`` (its ``check`` runs on
    ``params``; values in the units of ``softcell params``)."""
    return registry.get("integrator", name)(params)
