"""A nonlinear friction law applied between the force modes and the velocity modes, compiled
per law by :func:`softcell.engine.nonlinear_friction.compiled_friction`.

Bound: ``law_velocity`` (the law's velocity kernel), ``ANALYTIC`` (whether ``law_derivative``,
the law's derivative kernel, is bound; otherwise central differences of ``law_velocity``) and
``LEAN_JIT_FLAGS``. ``lw`` is the workspace of
:func:`softcell.engine.nonlinear_friction.workspace`.
"""

from typing import TYPE_CHECKING

from numba import njit

from softcell.engine.kernels.friction_modes import (
    apply_to_rows,
    force_field,
    law_matrix,
    shape_field,
    velocity_modes,
)

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        law_velocity,
        law_derivative,
        ANALYTIC,
        LEAN_JIT_FLAGS,
    ) = (None,) * 4


#: The names this template expects the loader to bind (besides the numba flags); a missing
#: or an extra binding is an error naming the template.
BOUND = (
    "law_velocity",
    "law_derivative",
    "ANALYTIC",
)


@njit(**LEAN_JIT_FLAGS)
def velocity(modes, fhat, vhat, lw):
    """vhat (cm s^-1): the velocity modes |k| <= Lc of the membrane with modes ``modes`` (cm)
    under the force modes ``fhat`` (N per unit xi); leaves the membrane's points and
    tangents in ``lw.x, lw.y, lw.tx, lw.ty`` and the force density in ``lw.fx, lw.fy`` for
    :func:`jacobian`."""
    shape_field(modes, lw.spec, lw.field, lw.x, lw.y, lw.tx, lw.ty)
    force_field(fhat, lw.scale[0], lw.spec, lw.field, lw.fx, lw.fy)
    law_velocity(lw.x, lw.y, lw.tx, lw.ty, lw.fx, lw.fy, lw.coefficients, lw.vx, lw.vy)
    velocity_modes(lw.vx, lw.vy, lw.spec, lw.field, vhat)


@njit(**LEAN_JIT_FLAGS)
def derivative(lw):
    """d v / d f at the force density in ``lw.fx, lw.fy`` (the membrane held where
    :func:`velocity` left it) into ``lw.dxx ... lw.dyy``."""
    coefficients = lw.coefficients
    x, y, tx, ty = lw.x, lw.y, lw.tx, lw.ty
    if ANALYTIC:
        law_derivative(x, y, tx, ty, lw.fx, lw.fy, coefficients, lw.dxx, lw.dxy, lw.dyx, lw.dyy)
        return
    n = lw.fx.size
    for axis in range(2):
        for sign in range(2):
            for i in range(n):
                lw.fx_step[i] = lw.fx[i]
                lw.fy_step[i] = lw.fy[i]
                if axis == 0:
                    h = 1e-6 * (abs(lw.fx[i]) + 1e-8)
                    lw.fx_step[i] += h if sign == 0 else -h
                else:
                    h = 1e-6 * (abs(lw.fy[i]) + 1e-8)
                    lw.fy_step[i] += h if sign == 0 else -h
            if sign == 0:
                law_velocity(
                    x, y, tx, ty, lw.fx_step, lw.fy_step, coefficients, lw.vx_plus, lw.vy_plus
                )
            else:
                law_velocity(x, y, tx, ty, lw.fx_step, lw.fy_step, coefficients, lw.vx, lw.vy)
        for i in range(n):
            f = lw.fx[i] if axis == 0 else lw.fy[i]
            inv = 0.5 / (1e-6 * (abs(f) + 1e-8))
            if axis == 0:
                lw.dxx[i] = (lw.vx_plus[i] - lw.vx[i]) * inv
                lw.dyx[i] = (lw.vy_plus[i] - lw.vy[i]) * inv
            else:
                lw.dxy[i] = (lw.vx_plus[i] - lw.vx[i]) * inv
                lw.dyy[i] = (lw.vy_plus[i] - lw.vy[i]) * inv


@njit(**LEAN_JIT_FLAGS)
def jacobian(jac, lw):
    """The force modes' rows of ``jac`` (d f_hat / d u, at the state whose force density
    :func:`velocity` left in ``lw``) become the velocity modes' rows."""
    lc = (lw.vhat.size - 1) // 2
    derivative(lw)
    law_matrix(
        lw.dxx, lw.dxy, lw.dyx, lw.dyy, lw.scale[0], lc, lw.buf, lw.spec, lw.a_hat, lw.b_hat, lw.law
    )
    apply_to_rows(lw.law, jac, lw.rows)
