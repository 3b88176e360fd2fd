"""rodas4's force modes and Jacobian contributions of one group of energy terms on one grid,
compiled per group by :func:`softcell.integrators.rodas4.compiled_loop`.

Bound: ``partials`` and ``hessian`` (the group's composed kernels), ``SCAN`` (bool) and
``LEAN_JIT_FLAGS``. With ``SCAN`` False, second derivatives are taken to vanish where all partials
do (true of the contact, which vanishes beyond its cut-off) and only those points are visited;
otherwise (the fallback's differences, or a small grid) every point is scanned.
"""

from typing import TYPE_CHECKING

from numba import njit
from rocket_fft import c2c

from softcell.engine.kernels.jacobian import SPARSE_POINTS, active_points, assemble_jacobian
from softcell.engine.kernels.spectral import AXES, assemble, derivative_bins

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        partials,
        hessian,
        SCAN,
        LEAN_JIT_FLAGS,
    ) = (None,) * 4


#: The names this template expects the loader to bind (besides the numba flags); a missing
#: or an extra binding is an error naming the template.
BOUND = (
    "partials",
    "hessian",
    "SCAN",
)


@njit(**LEAN_JIT_FLAGS)
def forces(modes, pose, order, context, coefficients, g):
    """g.fhat (N) and g.dpose of the group at these modes; curve derivatives above
    ``order`` are left at zero, and so are the partials with respect to them (the energy
    term contract: a term's partials beyond its ``derivative_order`` are zero), which are
    neither reset nor scanned."""
    n = g.w.shape[1]
    lc = (modes.size - 1) // 2
    for o in range(order + 1):
        derivative_bins(modes, o, g.spec)  # g.spec holds nothing else
        c2c(g.spec, g.curve[o], AXES, False, 1.0, 1)
        for i in range(n):
            g.w[2 * o, i] = g.curve[o, i].real
            g.w[2 * o + 1, i] = g.curve[o, i].imag
    _reset(g.parts, 2 * order + 2, g.touched, g.n_touched[0])
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
    count, first, second = _scan(p, order, g)
    if first or second or count > SPARSE_POINTS:
        # FFTs, skipping the orders whose partials vanish everywhere (those above ``order``
        # always do, and their rows of q are not read).
        for o in range(order + 1):
            for i in range(n):
                g.q[o, i] = complex(p[2 * o, i], p[2 * o + 1, i])
        assemble(g.q[0], g.q[1], g.q[2], count > 0, first, second, g.scratch, g.fhat)
    else:
        _direct_modes(p, count, lc, g)


@njit(**LEAN_JIT_FLAGS)
def _reset(parts, rows, touched, count):
    """Zero the first ``rows`` rows of ``parts`` where the last call left partials
    (``touched[:count]``, which :func:`_scan` lists): the rest are zero already. A grid
    where most points carried partials is zeroed whole."""
    if 4 * count > parts.shape[1]:
        parts[:rows, :] = 0.0
        return
    for t in range(count):
        i = touched[t]
        for r in range(rows):
            parts[r, i] = 0.0


@njit(**LEAN_JIT_FLAGS)
def _scan(p, order, g):
    """List in g.index the points where the zeroth-order partials are nonzero and in
    g.active those where any is (their count in g.n_active, and a copy in g.touched for
    :func:`_reset`: g.active may be rewritten by the Jacobian); return the first count and
    whether any first- and second-order partial is nonzero."""
    n = p.shape[1]
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
            g.touched[n_active] = i
            n_active += 1
    g.n_active[0] = n_active
    g.n_touched[0] = n_active
    return count, first, second


@njit(**LEAN_JIT_FLAGS)
def _direct_modes(p, count, lc, g):
    """g.fhat from the zeroth-order partials at the ``count`` points of g.index (only a few
    carry a force, the contact): direct sums, no FFT, point by point (the sum of each mode
    still runs over the points in order). The twiddle index (k i) mod N of a point is
    stepped by i from k to k + 1 (N a power of two)."""
    n = p.shape[1]
    inv = 1.0 / n
    mask = n - 1
    m = g.fhat.size
    for j in range(m):
        g.fhat[j] = 0.0 + 0.0j
    for t in range(count):
        i = g.index[t]
        value = complex(p[0, i], p[1, i])
        c = (-lc * i) & mask
        for j in range(m):
            g.fhat[j] += value * g.twiddle[c]
            c = (c + i) & mask
    for j in range(m):
        g.fhat[j] = -g.fhat[j] * inv


@njit(**LEAN_JIT_FLAGS)
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
