"""Slow, readable twins of the compiled kernels: plain Python loops written from the
definitions of docs/model.md, with nothing shared with the code they check (no FFT, no
numba). ``tests/test_naive_twins.py`` compares each kernel with its twin.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar


def curve(modes: np.ndarray, n: int, order: int = 0) -> list[complex]:
    """The ``order``-th xi-derivative of z(xi) = sum_k g_k exp(i k xi) at xi_m = 2 pi m / n,
    summed term by term (cm)."""
    lc = (len(modes) - 1) // 2
    out = []
    for m in range(n):
        xi = 2 * math.pi * m / n
        z = 0j
        for j, g in enumerate(modes):
            k = j - lc
            z += g * (1j * k) ** order * complex(math.cos(k * xi), math.sin(k * xi))
        out.append(z)
    return out


def signed_distance(px: float, py: float, a: float, b: float) -> float:
    """Distance from (px, py) to the ellipse x^2/a^2 + y^2/b^2 = 1 in its own frame, negative
    inside: the closest of 4000 points of the boundary, refined by Brent's method on the
    boundary's angle parameter."""

    def squared(t: float) -> float:
        return (px - a * math.cos(t)) ** 2 + (py - b * math.sin(t)) ** 2

    grid = [2 * math.pi * i / 4000 for i in range(4000)]
    best = min(grid, key=squared)
    step = 2 * math.pi / 4000
    found = minimize_scalar(
        squared, bounds=(best - step, best + step), method="bounded", options={"xatol": 1e-13}
    )
    distance = math.sqrt(min(squared(found.x), squared(best)))
    inside = (px / a) ** 2 + (py / b) ** 2 < 1.0
    return -distance if inside else distance


def energy(
    modes: np.ndarray,
    n: int,
    params,
    pose=(0.0, 0.0, 0.0),
    terms=("bending", "tension", "contact"),
    contact_cutoff: float = 25.0,
) -> float:
    """E = (2 pi / n) sum_m e_m (N cm) of the chosen terms, each density from its formula:
    bending k kappa^2 s, tension alpha (l0 / 2 pi) (2 pi s - l0)^2, contact
    (l0 / 2 pi) A exp(-rho / lambda) within ``contact_cutoff`` lambda of the bot."""
    z, zp, zpp = (curve(modes, n, o) for o in (0, 1, 2))
    l0 = 2 * math.pi * float(params["radius"])
    total = 0.0
    for m in range(n):
        s = abs(zp[m])
        e = 0.0
        if "bending" in terms:
            kappa = (zp[m].real * zpp[m].imag - zp[m].imag * zpp[m].real) / s**3
            e += params["bending_stiffness"] * kappa**2 * s
        if "tension" in terms:
            e += params["tension"] * l0 / (2 * math.pi) * (2 * math.pi * s - l0) ** 2
        if "contact" in terms:
            c, si = math.cos(pose[2]), math.sin(pose[2])
            dx, dy = z[m].real - pose[0], z[m].imag - pose[1]
            rho = signed_distance(
                c * dx + si * dy,
                -si * dx + c * dy,
                params["bot_semi_major"],
                params["bot_semi_minor"],
            )
            if rho <= contact_cutoff * params["contact_length"]:
                e += (
                    l0
                    / (2 * math.pi)
                    * params["contact_amplitude"]
                    * math.exp(-rho / params["contact_length"])
                )
        total += e
    return 2 * math.pi / n * total


def force_modes(
    modes: np.ndarray,
    n: int,
    params,
    pose=(0.0, 0.0, 0.0),
    terms=("bending", "tension", "contact"),
    step: float = 1e-6,
) -> np.ndarray:
    """f_hat_k from central differences of :func:`energy`:
    dE/dRe(g_k) + i dE/dIm(g_k) = -2 pi f_hat_k (docs/model.md §3)."""
    out = np.zeros(len(modes), dtype=complex)
    for j in range(len(modes)):
        grad = []
        for direction in (1.0, 1j):
            plus, minus = modes.copy(), modes.copy()
            plus[j] += step * direction
            minus[j] -= step * direction
            grad.append(
                (energy(plus, n, params, pose, terms) - energy(minus, n, params, pose, terms))
                / (2 * step)
            )
        out[j] = -(grad[0] + 1j * grad[1]) / (2 * math.pi)
    return out


def msd(positions: np.ndarray) -> list[float]:
    """<|r(i + m) - r(i)|^2> over the pairs of rows with no NaN, at every lag m (NaN where
    there is no pair)."""
    rows = [list(r) for r in np.asarray(positions, dtype=float)]
    valid = [all(math.isfinite(x) for x in r) for r in rows]
    out = []
    for lag in range(len(rows)):
        total, pairs = 0.0, 0
        for i in range(len(rows) - lag):
            if valid[i] and valid[i + lag]:
                total += sum((x1 - x0) ** 2 for x0, x1 in zip(rows[i], rows[i + lag], strict=True))
                pairs += 1
        out.append(total / pairs if pairs else math.nan)
    return out


def solve(matrix: np.ndarray, rhs: np.ndarray) -> list[float]:
    """x with A x = b by Gaussian elimination with partial pivoting, on lists."""
    a = [list(map(float, row)) + [float(v)] for row, v in zip(matrix, rhs, strict=True)]
    n = len(a)
    for col in range(n):
        pivot = max(range(col, n), key=lambda r: abs(a[r][col]))
        a[col], a[pivot] = a[pivot], a[col]
        for r in range(col + 1, n):
            factor = a[r][col] / a[col][col]
            for c in range(col, n + 1):
                a[r][c] -= factor * a[col][c]
    x = [0.0] * n
    for r in reversed(range(n)):
        x[r] = (a[r][n] - sum(a[r][c] * x[c] for c in range(r + 1, n))) / a[r][r]
    return x


def phases(labels, segment) -> list[tuple[int, int, int]]:
    """(first sample, number of samples, label) of each run of equal labels within a segment
    that is neither the first nor the last of its segment and touches no unknown (-1)
    sample."""
    runs = []  # [first, length, label, segment]
    for i, (label, seg) in enumerate(zip(labels, segment, strict=True)):
        if runs and runs[-1][2] == label and runs[-1][3] == seg:
            runs[-1][1] += 1
        else:
            runs.append([i, 1, label, seg])
    kept = []
    for r, (first, length, label, seg) in enumerate(runs):
        before = runs[r - 1] if r > 0 else None
        after = runs[r + 1] if r + 1 < len(runs) else None
        opens = before is None or before[3] != seg or before[2] < 0
        closes = after is None or after[3] != seg or after[2] < 0
        if label >= 0 and not opens and not closes:
            kept.append((first, length, label))
    return kept
