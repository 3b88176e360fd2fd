"""The documented fallback for an energy term without analytic second derivatives: central
differences of its partials kernel (see :func:`softcell.engine.model.compose_hessians`).

Bound: ``partials`` (the term's partials kernel), ``LEAN_JIT_FLAGS``.

A term's partials at point n depend only on the point's own w_n and on the pose, so one
perturbation of component b at *all* points gives column b of every point's Hessian:
2 x (6 + 3) kernel calls in all. Steps: ``steps[0:6]`` for w (cm), ``steps[6:9]`` for the
pose (cm, cm, rad). The results are *added* to ``hww``, ``hwp`` and ``hpp``.
"""

from typing import TYPE_CHECKING

from numba import njit

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        partials,
        LEAN_JIT_FLAGS,
    ) = (None,) * 2


#: The names this template expects the loader to bind (besides the numba flags); a missing
#: or an extra binding is an error naming the template.
BOUND = ("partials",)


@njit(**LEAN_JIT_FLAGS)
def fd_hessian(
    w,
    pose,
    context,
    coefficients,
    steps,
    saved,
    plus,
    minus,
    dplus,
    dminus,
    pose_tmp,
    hww,
    hwp,
    hpp,
):
    n = w.shape[1]
    for b in range(6):
        h = steps[b]
        for i in range(n):
            saved[i] = w[b, i]
        for i in range(n):
            w[b, i] = saved[i] + h
        plus[:, :] = 0.0
        dplus[:] = 0.0
        partials(
            w[0],
            w[1],
            w[2],
            w[3],
            w[4],
            w[5],
            pose,
            context,
            coefficients,
            plus[0],
            plus[1],
            plus[2],
            plus[3],
            plus[4],
            plus[5],
            dplus,
        )
        for i in range(n):
            w[b, i] = saved[i] - h
        minus[:, :] = 0.0
        dminus[:] = 0.0
        partials(
            w[0],
            w[1],
            w[2],
            w[3],
            w[4],
            w[5],
            pose,
            context,
            coefficients,
            minus[0],
            minus[1],
            minus[2],
            minus[3],
            minus[4],
            minus[5],
            dminus,
        )
        for i in range(n):
            w[b, i] = saved[i]
        inv = 0.5 / h
        for a in range(6):
            for i in range(n):
                hww[i, a, b] += (plus[a, i] - minus[a, i]) * inv
    for c in range(3):
        h = steps[6 + c]
        for d in range(3):
            pose_tmp[d] = pose[d]
        pose_tmp[c] = pose[c] + h
        plus[:, :] = 0.0
        dplus[:] = 0.0
        partials(
            w[0],
            w[1],
            w[2],
            w[3],
            w[4],
            w[5],
            pose_tmp,
            context,
            coefficients,
            plus[0],
            plus[1],
            plus[2],
            plus[3],
            plus[4],
            plus[5],
            dplus,
        )
        pose_tmp[c] = pose[c] - h
        minus[:, :] = 0.0
        dminus[:] = 0.0
        partials(
            w[0],
            w[1],
            w[2],
            w[3],
            w[4],
            w[5],
            pose_tmp,
            context,
            coefficients,
            minus[0],
            minus[1],
            minus[2],
            minus[3],
            minus[4],
            minus[5],
            dminus,
        )
        inv = 0.5 / h
        for a in range(6):
            for i in range(n):
                hwp[i, a, c] += (plus[a, i] - minus[a, i]) * inv
        for d in range(3):
            hpp[d, c] += (dplus[d] - dminus[d]) * inv
