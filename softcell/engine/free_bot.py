"""The free bot (no membrane): exact phase-by-phase kinematics and its renewal theory.

Without a membrane the bot's motion within a phase is known in closed form: a run is a
straight line at v = F0 / gamma_T; a tumble is a rotation at omega = T0 / gamma_R about the
bot's center or about a pivot offset d along the minor axis. Long free-bot statistics
(docs/model.md §5) therefore cost nothing.

Renewal formula. Take a cycle = one run then one tumble. In the frame of the heading at the
cycle start, the cycle displaces the bot by b = v tau_r + s_p d (i - i e^{i phi}) (complex
notation; s_p the pivot side, 0 offset for rotation about the center) and turns it by
phi = s omega tau_t. Cycles are independent, so with m = <b>, w = <conj(b) e^{i phi}> and
c = <e^{i phi}> the long-time diffusion coefficient (MSD -> 4 D t) is

    D = [<|b|^2> + 2 Re(w m / (1 - c))] / (4 <tau_r + tau_t>).
"""

from __future__ import annotations

import numpy as np

from softcell.model.parameters import Parameters


def _kinematics(params: Parameters) -> tuple[float, float, float]:
    v = float(params.drive_force) / float(params.bot_friction)
    omega = float(params.drive_torque) / float(params.bot_rotational_friction)
    return v, omega, float(params.pivot_offset)


def _pivot_side(sign: np.ndarray, pivot: str | None) -> np.ndarray:
    if pivot is None:
        return np.zeros_like(sign)
    if pivot == "inner":
        return sign
    if pivot == "fixed":
        return np.ones_like(sign)
    raise ValueError(f"pivot must be None, 'inner' or 'fixed', not {pivot!r}")


def cycle_displacements(
    params: Parameters, rng: np.random.Generator, cycles: int, pivot: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Exact world-frame displacement (complex, cm) and duration (s) of ``cycles`` run+tumble
    cycles of the free bot, starting with heading 0.

    ``pivot``: None (rotation about the center, as ``run_and_tumble``), ``"inner"`` or
    ``"fixed"`` (as ``pivot_run_and_tumble``).
    """
    v, omega, d = _kinematics(params)
    lo, hi = float(params.phase_min), float(params.phase_max)
    tau_r = rng.uniform(lo, hi, cycles)
    tau_t = rng.uniform(lo, hi, cycles)
    sign = rng.choice(np.array([-1.0, 1.0]), cycles)
    phi = sign * omega * tau_t
    side = _pivot_side(sign, pivot)
    body = v * tau_r + side * d * (1j - 1j * np.exp(1j * phi))
    heading = np.concatenate([[0.0], np.cumsum(phi)[:-1]])
    return np.exp(1j * heading) * body, tau_r + tau_t


def diffusion_from_cycles(displacement: np.ndarray, duration: np.ndarray, lags: int = 5) -> float:
    """Long-time D (MSD -> 4 D t, cm^2/s) from a sequence of cycle displacements: the sum of
    their empirical correlations up to ``lags`` cycles over four times the mean cycle time."""
    total = np.mean(np.abs(displacement) ** 2)
    for lag in range(1, lags + 1):
        total += 2 * np.mean((np.conj(displacement[:-lag]) * displacement[lag:]).real)
    return float(total / (4 * np.mean(duration)))


def turn_correlation(params: Parameters) -> float:
    """<cos(omega tau)> over a tumble, tau ~ U[phase_min, phase_max] (-0.1824 with the
    defaults, docs/model.md §5)."""
    _, omega, _ = _kinematics(params)
    lo, hi = float(params.phase_min), float(params.phase_max)
    return float(_uniform_exp(1j * omega, lo, hi).real)


def _uniform_exp(k: complex, lo: float, hi: float) -> complex:
    """<exp(k tau)> for tau ~ U[lo, hi]: exp(k m) sinh(k h) / (k h) with m, h the midpoint and
    half-width, a form without the cancellation of (e^{k hi} - e^{k lo}) / (k (hi - lo)) when
    hi is close to lo (a series below |k h| = 1e-4)."""
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    z = k * half
    ratio = np.sinh(z) / z if abs(z) > 1e-4 else 1 + z * z / 6 + z**4 / 120
    return complex(np.exp(k * mid) * ratio)


def renewal_diffusion(params: Parameters, pivot: str | None = None) -> float:
    """The renewal formula for the free bot's long-time D (cm^2/s, MSD -> 4 D t).

    Expectations over tau ~ U[phase_min, phase_max] and the turn sign are exact (closed-form
    moments of the uniform law).
    """
    v, omega, d = _kinematics(params)
    lo, hi = float(params.phase_min), float(params.phase_max)
    mean_tau = 0.5 * (lo + hi)
    mean_tau2 = (hi * hi + hi * lo + lo * lo) / 3

    def e_exp(k: complex) -> complex:  # <exp(k tau)>, tau ~ U[lo, hi]
        return _uniform_exp(k, lo, hi)

    # Average over the sign s = +-1 of functions of phi = s omega tau.
    c = 0.5 * (e_exp(1j * omega) + e_exp(-1j * omega))
    if pivot is None:
        m, w = v * mean_tau, v * mean_tau * c
        b2 = v**2 * mean_tau2
    else:
        terms = []
        for s in (-1.0, 1.0):
            sp = s if pivot == "inner" else 1.0
            e1 = e_exp(1j * s * omega)  # <e^{i phi}>
            # pivot part p = sp d i (1 - e^{i phi})
            mp = sp * d * 1j * (1 - e1)
            # <conj(b) e^{i phi}> with b = v tau_r + p, tau_r independent of phi
            wp = v * mean_tau * e1 + np.conj(sp * d * 1j) * (e1 - 1.0)
            # <|b|^2> = v^2 <tau^2> + 2 v <tau> Re<p> + <|p|^2>, |p|^2 = 2 d^2 (1 - cos phi)
            b2p = v**2 * mean_tau2 + 2 * v * mean_tau * mp.real + 2 * d**2 * (1 - e1.real)
            terms.append((v * mean_tau + mp, wp, b2p))
        m = 0.5 * (terms[0][0] + terms[1][0])
        w = 0.5 * (terms[0][1] + terms[1][1])
        b2 = 0.5 * (terms[0][2] + terms[1][2])
    return float((b2 + 2 * (w * m / (1 - c)).real) / (4 * 2 * mean_tau))


def firmware_diffusion(
    speed: float, turn_rate: float, durations: np.ndarray, pivot_ccw: float, pivot_cw: float
) -> float:
    """The renewal formula above for a bot whose runs and tumbles last one of ``durations``
    (s, equally likely, drawn independently) and whose tumbles pivot on the inner side of
    the turn, ``pivot_ccw`` (cm) off centre turning counterclockwise and ``pivot_cw`` (cm)
    clockwise, at ``turn_rate`` (rad/s); runs go at ``speed`` (cm/s). The expectations are
    exact finite sums over the durations and the two turn signs.

    Returns
    -------
    float
        The long-time diffusion coefficient D (cm^2/s, MSD -> 4 D t).
    """
    tau = np.asarray(durations, dtype=np.float64)
    mean_tau, mean_tau2 = float(tau.mean()), float(np.mean(tau**2))
    # The tumbles: both signs, each duration; p = s d_s i (1 - e^{i phi}), phi = s omega tau.
    sign = np.concatenate([np.ones(tau.size), -np.ones(tau.size)])
    offset = np.where(sign > 0, pivot_ccw, pivot_cw)
    phi = sign * turn_rate * np.concatenate([tau, tau])
    turn = np.exp(1j * phi)
    p = sign * offset * 1j * (1 - turn)
    c = turn.mean()
    m = speed * mean_tau + p.mean()
    w = speed * mean_tau * c + np.mean(np.conj(p) * turn)
    b2 = speed**2 * mean_tau2 + 2 * speed * mean_tau * p.real.mean() + np.mean(np.abs(p) ** 2)
    return float((b2 + 2 * (w * m / (1 - c)).real) / (4 * 2 * mean_tau))
