"""rodas4's force modes and Jacobian contributions of one group of energy terms on one grid,
compiled per group by :func:`softcell.plugins.rodas4.compiled_loop`.

Bound: ``partials`` and ``hessian`` (the group's composed kernels), ``SCAN`` (bool) and
``JIT_FLAGS``. With ``SCAN`` False, second derivatives are taken to vanish where all partials
do (true of the contact, which vanishes beyond its cut-off) and only those points are visited;
otherwise (the fallback's differences, or a small grid) every point is scanned.
"""
# ruff: noqa: F821 (the names of BOUND are bound by the loader, with JIT_FLAGS)

from numba import njit
from rocket_fft import c2c

from softcell.kernels.jacobian import SPARSE_POINTS, active_points, assemble_jacobian
from softcell.kernels.spectral import AXES, assemble, derivative_spectrum

#: The names this template expects the loader to bind (besides ``JIT_FLAGS``); a missing
#: or an extra binding is an error naming the template.
BOUND = (
    "partials",
    "hessian",
    "SCAN",
)


@njit(**JIT_FLAGS)
def forces(modes, pose, order, context, coefficients, g):
    """g.fhat (N) and g.dpose of the group at these modes; curve derivatives above
    ``order`` are left at zero, and so are the partials with respect to them (the energy
    term contract: a term's partials beyond its ``derivative_order`` are zero), which are
    neither reset nor scanned."""
    n = g.w.shape[1]
    lc = (modes.size - 1) // 2
    for o in range(order + 1):
        derivative_spectrum(modes, o, g.spec)
        c2c(g.spec, g.curve[o], AXES, False, 1.0, 1)
        for i in range(n):
            g.w[2 * o, i] = g.curve[o, i].real
            g.w[2 * o + 1, i] = g.curve[o, i].imag
    rows = 2 * order + 2
    g.parts[:rows, :] = 0.0
    g.dpose[:] = 0.0
    p = g.parts
    partials(
        g.w[0],
        g.w[1],
        g.w[2],
        g.w[3],
        g.w[4],
        g.w[5],
        pose,
        context,
        coefficients,
        p[0],
        p[1],
        p[2],
        p[3],
        p[4],
        p[5],
        g.dpose,
    )
    count = 0
    n_active = 0
    first = False
    second = False
    for i in range(n):
        zero = True
        if p[0, i] != 0.0 or p[1, i] != 0.0:
            g.index[count] = i
            count += 1
            zero = False
        if order >= 1 and (p[2, i] != 0.0 or p[3, i] != 0.0):
            first = True
            zero = False
        if order == 2 and (p[4, i] != 0.0 or p[5, i] != 0.0):
            second = True
            zero = False
        if not zero:
            g.active[n_active] = i
            n_active += 1
    g.n_active[0] = n_active
    if first or second or count > SPARSE_POINTS:
        # FFTs, skipping the orders whose partials vanish everywhere.
        for i in range(n):
            for o in range(3):
                g.q[o, i] = complex(p[2 * o, i], p[2 * o + 1, i])
        assemble(g.q[0], g.q[1], g.q[2], count > 0, first, second, g.spec, g.fhat)
    else:
        # Only a few points carry a force (the contact): direct sums, no FFT.
        # The twiddle index (k i) mod N of each point is stepped by i from k to k + 1.
        inv = 1.0 / n
        for t in range(count):
            i = g.index[t]
            g.cursor[t] = (-lc * i) % n
            g.scratch[t] = complex(p[0, i], p[1, i])
        for j in range(modes.size):
            acc = 0.0 + 0.0j
            for t in range(count):
                acc += g.scratch[t] * g.twiddle[g.cursor[t]]
                c = g.cursor[t] + g.index[t]
                g.cursor[t] = c - n if c >= n else c
            g.fhat[j] = -acc * inv


@njit(**JIT_FLAGS)
def grid_jacobian(pose, context, coefficients, mobility, bot_mobility, g, ws):
    """Add the group's part of the Jacobian into ws.jac; g.w must hold the curve and
    g.active the points where the last :func:`forces` at this state found partials."""
    hessian(
        g.w,
        pose,
        context,
        coefficients,
        ws.steps,
        g.saved,
        g.plus,
        g.minus,
        ws.dplus,
        ws.dminus,
        ws.pose_tmp,
        g.hww,
        g.hwp,
        g.hpp,
    )
    if SCAN:
        n_active = active_points(g.hww, g.hwp, g.active)
    else:
        n_active = g.n_active[0]
    assemble_jacobian(
        g.hww,
        g.hwp,
        g.hpp,
        (ws.modes.size - 1) // 2,
        mobility,
        bot_mobility,
        g.twiddle,
        g.index,
        g.active,
        n_active,
        g.buf_a,
        g.buf_b,
        g.scratch,
        g.cursor,
        ws.a_hat,
        ws.b_hat,
        ws.g_hat,
        ws.cal_a,
        ws.cal_b,
        ws.factors,
        ws.orders,
        ws.magnitudes,
        ws.rotated,
        ws.jac,
    )
