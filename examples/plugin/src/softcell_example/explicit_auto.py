"""An integrator: the paper's explicit Euler scheme at the largest step its stability bound
allows, rounded down to divide the sampling intervals (for coarse test membranes this is far
larger than the paper's 1e-6 s). It reuses softcell's explicit stepper: an integrator's job is
to return a ``Stepper`` from ``build(model)``.
"""

import math

from softcell.plugin import Integrator, ParameterError, ParameterSpec
from softcell.plugin.blocks import ExplicitEulerStepper, explicit_decay_rate

SAFETY = ParameterSpec(
    "stability_fraction",
    0.5,
    "1",
    "step as a fraction of the explicit stability limit 2 / lambda_max",
    minimum=0.0,
    maximum=1.0,
)


class ExplicitAuto(Integrator):
    """Explicit Euler at dt = fraction * 2 / lambda_max, divided down to fit the sampling."""

    name = "explicit_auto"
    description = "explicit Euler at a fraction of its stability limit (no dt to choose)"
    parameters = (SAFETY,)

    def step(self, model) -> float:
        """The step (s) for ``model``: the stability bound times the fraction, then the
        largest 1e-6 s multiple that divides every sampling interval below it."""
        limit = (
            float(self.params["stability_fraction"]) * 2.0 / explicit_decay_rate(model)
            if model.has_membrane
            else 1e-3
        )
        p = model.params
        base = 1e-6
        grid = math.gcd(
            *(
                round(float(p[n]) / base)
                for n in ("sample_every", "sample_every_late", "sample_switch")
            )
        )
        steps = (
            max(d for d in range(1, grid + 1) if grid % d == 0 and d * base <= limit)
            if limit >= base
            else 0
        )
        if steps == 0:
            raise ParameterError(
                "stability_fraction",
                self.params["stability_fraction"],
                f"gives a step below 1e-6 s (limit {limit:.3g} s)",
                "1",
            )
        return steps * base

    def build(self, model):
        return ExplicitEulerStepper(model, self.step(model))
