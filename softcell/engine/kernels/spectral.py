"""Spectral evaluation of the membrane and spectral assembly of its force (SI steps 1-4).

The membrane z = x + i y is the trigonometric polynomial z(xi) = sum_{|k| <= Lc} g_k e^{i k xi};
``modes[j]`` holds g_k for k = j - Lc. FFTs run inside compiled loops through rocket-fft
(pocketfft), which makes ``c2c`` callable from numba with preallocated outputs.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from rocket_fft import c2c

from softcell.settings import LEAN_JIT

#: The FFT axis of every 1-D transform (a module constant: no allocation per call).
AXES = np.zeros(1, dtype=np.int64)


@njit(**LEAN_JIT)
def wavenumber(j: int, n: int) -> int:
    """The wavenumber of FFT bin j of an n-point transform (0, 1, ..., n/2, -n/2+1, ..., -1)."""
    return j if j <= n // 2 else j - n


@njit(**LEAN_JIT)
def derivative_spectrum(modes, order, spec):
    """Fill ``spec`` (complex128[N]) with the N-point spectrum of the ``order``-th xi-derivative
    of the curve (0, 1 or 2): (i k)^order g_k in FFT bin k mod N, zero elsewhere."""
    spec[:] = 0.0
    derivative_bins(modes, order, spec)


@njit(**LEAN_JIT)
def derivative_bins(modes, order, spec):
    """:func:`derivative_spectrum` without clearing ``spec``: writes only the 2 Lc + 1 bins
    of the modes, so every other bin of ``spec`` must be zero already (a buffer that holds
    nothing else)."""
    n = spec.size
    lc = (modes.size - 1) // 2
    for j in range(modes.size):
        k = j - lc
        factor = 1.0 + 0.0j
        if order == 1:
            factor = 1j * k
        elif order == 2:
            factor = -(k * k) + 0.0j
        spec[k % n] = factor * modes[j]


@njit(**LEAN_JIT)
def evaluate(modes, spec, z, zp, zpp):
    """Curve and its first two xi-derivatives at the N = len(z) collocation points.

    ``modes``: complex128[2 Lc + 1] (cm); ``spec``: complex128[N] scratch;
    ``z, zp, zpp``: complex128[N] outputs (cm).
    """
    for order in range(3):
        derivative_spectrum(modes, order, spec)
        out = z if order == 0 else (zp if order == 1 else zpp)
        c2c(spec, out, AXES, False, 1.0, 1)


@njit(**LEAN_JIT)
def assemble(q0, q1, q2, has_q0, has_q1, has_q2, spec, fhat):
    """Force modes f_hat_k = -Q0_hat + i k Q1_hat + k^2 Q2_hat for |k| <= Lc (docs/model.md §3).

    ``q0, q1, q2``: complex128[N], the summed partials P0, P1, P2 as x + i y (N).
    ``has_q0, has_q1, has_q2``: False skips that transform (the partials of that order are
    zero everywhere: no bot contact for Q0, only the contact for Q1 and Q2).
    ``fhat``: complex128[2 Lc + 1] output (N), with f_hat_k = N^-1 sum_n f_n e^{-i k xi_n}.
    """
    n = q0.size
    lc = (fhat.size - 1) // 2
    axes = AXES
    inv = 1.0 / n
    fhat[:] = 0.0
    if has_q0:
        c2c(q0, spec, axes, True, inv, 1)
        for j in range(fhat.size):
            fhat[j] -= spec[(j - lc) % n]
    if has_q1:
        c2c(q1, spec, axes, True, inv, 1)
        for j in range(fhat.size):
            k = j - lc
            fhat[j] += 1j * k * spec[k % n]
    if has_q2:
        c2c(q2, spec, axes, True, inv, 1)
        for j in range(fhat.size):
            k = j - lc
            fhat[j] += (k * k) * spec[k % n]


def resample(modes: np.ndarray, points: int) -> np.ndarray:
    """The curve at ``points`` equally spaced xi, exactly (float64 [..., points] x and y).

    ``modes``: complex128[..., 2 Lc + 1]. Exact for any number of points: it evaluates the
    trigonometric polynomial, it does not interpolate. The same bytes whatever the number of
    BLAS threads of the process.
    """
    from threadpoolctl import threadpool_limits

    modes = np.asarray(modes)
    lc = (modes.shape[-1] - 1) // 2
    k = np.arange(-lc, lc + 1)
    xi = 2.0 * np.pi * np.arange(points) / points
    # One BLAS thread: the product's rounding depends on how many threads share it, and a
    # file must hold the same bytes whether a worker (one thread) or the command wrote it.
    with threadpool_limits(limits=1, user_api="blas"):
        z = modes @ np.exp(1j * np.outer(k, xi))
    return np.stack([z.real, z.imag])
