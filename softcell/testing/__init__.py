"""Helpers for testing softcell and softcell plugins.

- :func:`registered`: a context manager under which the process-wide registry also holds
  the given plugin modules or objects (register a plugin for one test, without installing it).
- :mod:`softcell.testing.strategies`: Hypothesis strategies (needs the ``test`` extra).
- :mod:`softcell.testing.camera`: camera-like footage of a simulated cell (a ray caster:
  perspective, lens, shadows, sensor noise, blur, compression), to test a tracker.
"""

from softcell.core.components.registry import registered

__all__ = ["registered"]
