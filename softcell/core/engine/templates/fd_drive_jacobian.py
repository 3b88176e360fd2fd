"""d drive / d pose by central differences of a drive kernel (steps ``steps[6:9]`` in cm, cm,
rad).

Bound: ``drive`` (the protocol's drive kernel), ``JIT_FLAGS``.
"""
# ruff: noqa: F821 (the names of BOUND are bound by the loader, with JIT_FLAGS)

from numba import njit

#: The names this template expects the loader to bind (besides ``JIT_FLAGS``); a missing
#: or an extra binding is an error naming the template.
BOUND = ("drive",)


@njit(**JIT_FLAGS)
def drive_jacobian(
    phase, datum, pose, context, drive_coefficients, steps, pose_tmp, plus, minus, out
):
    for d in range(3):
        h = steps[6 + d]
        pose_tmp[:] = pose
        pose_tmp[d] = pose[d] + h
        drive(phase, datum, pose_tmp, context, drive_coefficients, plus)
        pose_tmp[d] = pose[d] - h
        drive(phase, datum, pose_tmp, context, drive_coefficients, minus)
        for c in range(3):
            out[c, d] = (plus[c] - minus[c]) * (0.5 / h)
