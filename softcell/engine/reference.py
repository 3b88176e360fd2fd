"""The model evaluated with numpy: forces, energy and Jacobian for set-up, checks and tests.

Slow and readable, independent of the integrators' compiled force assembly, which the tests
compare against it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from softcell.engine.state import circle_modes, equilibrium_radius

if TYPE_CHECKING:
    from softcell.components.contracts import Model


def _curve(modes: np.ndarray, n: int) -> np.ndarray:
    """z, z', z'' (complex128[3, n], cm) at n collocation points, with numpy FFTs."""
    lc = (modes.size - 1) // 2
    k = np.arange(-lc, lc + 1)
    spectrum = np.zeros((3, n), dtype=np.complex128)
    for order in range(3):
        spectrum[order, k % n] = (1j * k) ** order * modes
    return np.fft.ifft(spectrum, axis=1) * n


def force_modes(model: Model, modes: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Force modes and bot reaction for one state, with numpy FFTs (set-up, checks, tests).

    Returns
    -------
    fhat : complex128[2 Lc + 1]
        f_hat_k (N) for |k| <= Lc, with f_hat_k = N^-1 sum_n f_n e^{-i k xi_n}.
    dpose : float64[3]
        sum_n de_n/d(x_bot, y_bot, theta_bot); the reaction on the bot is -(2 pi / N) dpose.
    """
    n, lc = model.nodes, model.cutoff
    k = np.arange(-lc, lc + 1)
    z, zp, zpp = _curve(modes, n)
    parts = np.zeros((6, n))
    dpose = np.zeros(3)
    model.partials(
        z.real.copy(),
        z.imag.copy(),
        zp.real.copy(),
        zp.imag.copy(),
        zpp.real.copy(),
        zpp.imag.copy(),
        np.asarray(pose, dtype=np.float64),
        model.context,
        model.coefficients,
        *parts,
        dpose,
    )
    q = np.fft.fft(parts[0::2] + 1j * parts[1::2], axis=1)[:, k % n] / n
    return -q[0] + 1j * k * q[1] + (k * k) * q[2], dpose


def law_inputs(model: Model, modes: np.ndarray, pose: np.ndarray) -> list[np.ndarray]:
    """What a friction law's kernels receive at this state, with numpy FFTs: the membrane's
    points x, y (cm), unit tangents tx, ty and force density fx, fy (N cm^-1) at the M points
    where integrators apply the law (:func:`~softcell.engine.nonlinear_friction.law_nodes`),
    each float64[M]."""
    from softcell.engine.nonlinear_friction import law_nodes

    m = law_nodes(model.nodes, model.cutoff)
    lc = model.cutoff
    k = np.arange(-lc, lc + 1)
    fhat, _ = force_modes(model, modes, pose)
    spectrum = np.zeros(m, dtype=np.complex128)
    np.add.at(spectrum, k % m, fhat)
    f = np.fft.ifft(spectrum) * m * model.force_scale
    z, zp, _ = _curve(modes, m)
    t = zp / np.abs(zp)
    return [np.ascontiguousarray(a) for a in (z.real, z.imag, t.real, t.imag, f.real, f.imag)]


def total_energy(model: Model, modes: np.ndarray, pose: np.ndarray) -> float:
    """E = (2 pi / N) sum_n e_n over all terms (N cm), from the terms' ``density``."""
    n = model.nodes
    z, zp, zpp = _curve(modes, n)
    e = sum(
        t.density(z.real, z.imag, zp.real, zp.imag, zpp.real, zpp.imag, pose) for t in model.terms
    )
    return float(2 * np.pi / n * np.sum(e))


def explicit_decay_rate(model: Model) -> float:
    """Largest decay rate lambda_max (1/s) of the linearized explicit membrane update at the
    equilibrium circle (docs/model.md §2): the explicit Euler step is stable for dt lambda < 2.

    Parameters
    ----------
    model : Model
        The compiled model of one parameter point.
    """
    return float(np.max(-np.linalg.eigvals(membrane_jacobian(model)).real))


def membrane_jacobian(model: Model) -> np.ndarray:
    """Jacobian (1/s) of d(Re g, Im g)/dt at the equilibrium circle, bot at its center.

    Built by central differences (2 (2 Lc + 1) force evaluations); rows and columns are
    ordered Re g_{-Lc..Lc}, then Im g_{-Lc..Lc}.
    """
    lc = model.cutoff
    radius = equilibrium_radius(model.params)
    base = circle_modes(radius, lc)
    pose = np.array([0.0, 0.0, 0.0])  # the bot at the center feels and exerts nothing
    size = 2 * lc + 1
    jac = np.zeros((2 * size, 2 * size))
    h = 1e-6 * radius
    for j in range(2 * size):
        delta = np.zeros(size, dtype=np.complex128)
        delta[j % size] = h if j < size else 1j * h
        plus = force_modes(model, base + delta, pose)[0]
        minus = force_modes(model, base - delta, pose)[0]
        column = model.membrane_mobility * (plus - minus) / (2 * h)
        jac[:size, j], jac[size:, j] = column.real, column.imag
    return jac
