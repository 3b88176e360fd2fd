"""d drive / d pose by central differences of a drive kernel (steps ``steps[6:9]`` in cm, cm,
rad).

Bound: ``drive`` (the protocol's drive kernel), ``LEAN_JIT_FLAGS``.
"""

from typing import TYPE_CHECKING

from numba import njit

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        drive,
        LEAN_JIT_FLAGS,
    ) = (None,) * 2


#: The names this template expects the loader to bind (besides the numba flags); a missing
#: or an extra binding is an error naming the template.
BOUND = ("drive",)


@njit(**LEAN_JIT_FLAGS)
def drive_jacobian(
    phase, datum, pose, context, drive_coefficients, steps, pose_tmp, plus, minus, out
):
    for d in range(3):
        h = steps[6 + d]
        for c in range(3):
            pose_tmp[c] = pose[c]
        pose_tmp[d] = pose[d] + h
        drive(phase, datum, pose_tmp, context, drive_coefficients, plus)
        pose_tmp[d] = pose[d] - h
        drive(phase, datum, pose_tmp, context, drive_coefficients, minus)
        for c in range(3):
            out[c, d] = (plus[c] - minus[c]) * (0.5 / h)
