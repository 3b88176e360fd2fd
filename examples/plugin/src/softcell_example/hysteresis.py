"""A stop/go detector with hysteresis (a Schmitt trigger): a stop turns into go when the speed
reaches ``go_above``, a go turns into stop when it falls below ``stop_below`` (< go_above).
A noisy speed near one threshold then no longer flickers between stop and go.
"""

import numpy as np

from softcell.plugin import ParameterError, ParameterSpec, StopGoDetector


class Hysteresis(StopGoDetector):
    """Go from ``go_above`` up, stop from ``stop_below`` down, the previous label between."""

    name = "hysteresis"
    description = "stop/go with two thresholds: go from go_above up, stop below stop_below"
    parameters = (
        ParameterSpec(
            "go_above", 0.05, "cm s-1", "speed from which a stop becomes go", minimum=0.0
        ),
        ParameterSpec(
            "stop_below", 0.02, "cm s-1", "speed below which a go becomes stop", minimum=0.0
        ),
    )

    @classmethod
    def check(cls, params):
        if params["stop_below"] > params["go_above"]:
            raise ParameterError(
                "stop_below",
                params["stop_below"],
                f"must be <= go_above = {params['go_above']:g}",
                "cm s-1",
            )

    def label(self, speed, interval):
        speed = np.asarray(speed, dtype=np.float64)
        labels = np.full(speed.shape, -1, dtype=np.int8)
        state = np.full(speed.shape[:-1], -1, dtype=np.int8)  # -1: not yet known
        high, low = float(self.params["go_above"]), float(self.params["stop_below"])
        for t in range(speed.shape[-1]):
            s = speed[..., t]
            state = np.where(s >= high, 1, np.where(s < low, 0, state)).astype(np.int8)
            # Between the thresholds a series starts as stop when nothing came before.
            state = np.where((state < 0) & np.isfinite(s), 0, state).astype(np.int8)
            state = np.where(np.isnan(s), -1, state).astype(np.int8)
            labels[..., t] = state
        return labels
