"""The free active_brownian bot's D against the noise interval dt (docs/strategies.md).

Over intervals of dt the torque is constant, so the heading is piecewise linear: its change
over a lag s starting a fraction u into an interval is Gaussian with variance
(2 D_r / dt) * sum of the squared overlaps of [u dt, u dt + s] with the intervals. Then
C(s) = <cos dtheta> = <exp(-var / 2)>_u and D = (v^2 / 2) int_0^inf C(s) ds, computed here by
quadrature; the continuum limit is v^2 / (2 D_r). Run: python docs/strategies/convergence.py
"""

import numpy as np

V, DR = 0.04275 / 0.00285, 1.0  # cm/s (F0 / gamma_T), rad^2/s (the defaults)


def variance(s: np.ndarray, u: float, dt: float) -> np.ndarray:
    """Variance (rad^2) of the heading's change over lags s (s) begun u * dt into an interval."""
    start, end = u * dt, u * dt + s
    total = np.zeros_like(s)
    for k in range(int(np.ceil(end.max() / dt)) + 1):
        overlap = np.clip(np.minimum(end, (k + 1) * dt) - np.maximum(start, k * dt), 0, None)
        total += overlap**2
    return 2 * DR / dt * total


def diffusion(dt: float) -> float:
    s = np.linspace(0, 40 / DR, 200001)
    c = np.mean([np.exp(-variance(s, u, dt) / 2) for u in np.linspace(0, 1, 41)[:-1] + 1 / 80], 0)
    return float(V**2 / 2 * np.trapezoid(c, s))


if __name__ == "__main__":
    exact = V**2 / (2 * DR)
    print(f"continuum D = v^2 / (2 D_r) = {exact:.3f} cm^2/s")
    for dt in (0.4, 0.2, 0.1, 0.05, 0.025):
        d = diffusion(dt)
        print(f"dt = {dt:<6g} D = {d:.3f} cm^2/s  relative excess {d / exact - 1:+.4f}")
