"""Make the explicit reference the fast integrators are validated against.

Usage (from the repository root, ~15 min on one core)::

    python tests/regression/make_integrator_reference.py

For R = 4, 8 and 12 cm it runs realization 0 of root seed 0 (the heading and the phase
schedule drawn exactly as ``softcell simulate`` draws them) for 5 s with ``explicit_euler`` at
dt = 1e-6 s, sampled every 0.01 s, and stores the modes and the bot pose of every sample in
``integrator_reference.npz`` next to this file, with the softcell version and the command.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from softcell._version import __version__
from softcell.io.files import atomic_write
from softcell.testing.compare import parameters, run

RADII = (4.0, 8.0, 12.0)
DURATION = 5.0
SEED = 0
OUT = Path(__file__).with_name("integrator_reference.npz")


def main() -> None:
    arrays: dict[str, np.ndarray] = {}
    for radius in RADII:
        result = run(parameters(radius, DURATION, dt=1e-6), "explicit_euler", seed=SEED)
        key = f"r{radius:g}"
        arrays[f"{key}_times"] = result.record.times
        arrays[f"{key}_modes"] = result.record.modes
        arrays[f"{key}_pose"] = result.record.pose
        print(f"R = {radius:g} cm: {result.wall:.1f} s wall", flush=True)
    with atomic_write(OUT) as tmp:
        np.savez_compressed(
            tmp,
            radii=np.array(RADII),
            duration=DURATION,
            seed=SEED,
            version=__version__,
            command=" ".join(["python", *sys.argv]),
            **arrays,
        )


if __name__ == "__main__":
    main()
