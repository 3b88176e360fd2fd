"""The fallback for a bot energy without analytic second derivatives: central differences of
its kernel (see :func:`softcell.engine.compose.compose_bot`).

Bound: ``bot`` (the term's bot kernel), ``LEAN_JIT_FLAGS``. Steps ``steps[6:9]`` (cm, cm, rad); the
result is *added* to ``hpp``.
"""

from typing import TYPE_CHECKING

from numba import njit

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        bot,
        LEAN_JIT_FLAGS,
    ) = (None,) * 2


#: The names this template expects the loader to bind (besides the numba flags); a missing
#: or an extra binding is an error naming the template.
BOUND = ("bot",)


@njit(**LEAN_JIT_FLAGS)
def fd_bot_hessian(pose, context, coefficients, steps, pose_tmp, plus, minus, hpp):
    for d in range(3):
        h = steps[6 + d]
        for c in range(3):
            pose_tmp[c] = pose[c]
        pose_tmp[d] = pose[d] + h
        plus[:] = 0.0
        bot(pose_tmp, context, coefficients, plus)
        pose_tmp[d] = pose[d] - h
        minus[:] = 0.0
        bot(pose_tmp, context, coefficients, minus)
        for c in range(3):
            hpp[c, d] += (plus[c] - minus[c]) * (0.5 / h)
