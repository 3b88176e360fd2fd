"""A friction law: a membrane that slides along itself more easily than across.

The force density f on an element splits along the membrane's unit tangent t and its normal
n = (t_y, -t_x): v = (f . t) t / gamma_along + (f . n) n / gamma_across. With
gamma_along = gamma_across it is the paper's viscous law. It dissipates,
f . v = (f . t)^2 / gamma_along + (f . n)^2 / gamma_across >= 0, and its derivative at fixed
geometry is d v / d f = t t^T / gamma_along + n n^T / gamma_across.
"""

from numba import njit

from softcell.plugin import MODEL_PARAMETERS, FrictionLaw, ParameterSpec


@njit(nogil=True, cache=True)
def anisotropic_velocity(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    across, along = 1.0 / coefficients[0], 1.0 / coefficients[1]
    for n in range(fx.size):
        f_t = fx[n] * tx[n] + fy[n] * ty[n]  # along the tangent
        f_n = fx[n] * ty[n] - fy[n] * tx[n]  # along the normal (ty, -tx)
        vx[n] = along * f_t * tx[n] + across * f_n * ty[n]
        vy[n] = along * f_t * ty[n] - across * f_n * tx[n]


@njit(nogil=True, cache=True)
def anisotropic_derivative(x, y, tx, ty, fx, fy, coefficients, dxx, dxy, dyx, dyy):
    across, along = 1.0 / coefficients[0], 1.0 / coefficients[1]
    for n in range(fx.size):
        dxx[n] = along * tx[n] * tx[n] + across * ty[n] * ty[n]
        dxy[n] = (along - across) * tx[n] * ty[n]
        dyx[n] = dxy[n]
        dyy[n] = along * ty[n] * ty[n] + across * tx[n] * tx[n]


class Anisotropic(FrictionLaw):
    """v = (f . t) t / gamma_along + (f . n) n / gamma_across."""

    name = "anisotropic"
    description = "friction along the membrane differs from friction across it"
    parameters = (
        MODEL_PARAMETERS["membrane_friction"],  # across the membrane: the paper's gamma_mem
        ParameterSpec(
            "friction_along",
            1.71e-4,
            "N s cm-2",
            "membrane friction per unit length for sliding along itself",
            minimum=0.0,
        ),
    )

    def velocity_kernel(self):
        return anisotropic_velocity

    def derivative_kernel(self):
        return anisotropic_derivative
