"""Central differences of a bot interaction's kernel: the Jacobian the several-bot loop uses
for an interaction without a ``jacobian_kernel`` (docs/plugins.md, "class BotInteraction").

Bound: ``pair`` (the interaction's ``pair_kernel``) and ``LEAN_JIT_FLAGS``.
"""

from typing import TYPE_CHECKING

from numba import njit

if TYPE_CHECKING:  # bound by the loader before the module runs
    pair, LEAN_JIT_FLAGS = None, None

#: The names this template expects the loader to bind (besides the numba flags).
BOUND = ("pair",)


@njit(**LEAN_JIT_FLAGS)
def fd_interaction(pose_a, pose_b, context, coefficients, steps, scratch, jac):
    """Add (out(q + h e_j) - out(q - h e_j)) / (2 h) into ``jac[:, j]`` for the six pose
    coordinates q_j of the two bots (steps ``steps[6:9]`` in cm, cm, rad)."""
    plus, minus = scratch[0:6], scratch[6:12]
    qa, qb = scratch[12:15], scratch[15:18]
    for j in range(6):
        for c in range(3):
            qa[c] = pose_a[c]
            qb[c] = pose_b[c]
        h = steps[6 + j % 3]
        moved = qa if j < 3 else qb
        moved[j % 3] += h
        plus[:] = 0.0
        pair(qa, qb, context, coefficients, plus)
        moved[j % 3] -= 2.0 * h
        minus[:] = 0.0
        pair(qa, qb, context, coefficients, minus)
        for c in range(6):
            jac[c, j] += (plus[c] - minus[c]) / (2.0 * h)
