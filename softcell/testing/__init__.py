"""Helpers for testing softcell and softcell plugins.

- :func:`registered`: a context manager under which the process-wide registry also holds
  the given plugin modules or objects (register a plugin for one test, without installing it).
- :func:`check_component` (and :func:`check_energy_term`, :func:`check_friction_law`,
  :func:`check_driving_protocol`, :func:`check_stopgo_detector`, :func:`check_pair_term`,
  :func:`check_bot_interaction`): a
  component checked against
  its contract (:mod:`softcell.testing.checks`), for a plugin's tests.
- :mod:`softcell.testing.strategies`: Hypothesis strategies (needs the ``test`` extra).
- :mod:`softcell.testing.footage`: camera-like footage of a simulated cell (a ray caster:
  perspective, lens, shadows, sensor noise, blur, compression), to test a tracker.
"""

from softcell.components.registry import registered
from softcell.testing.checks import (
    check_bot_interaction,
    check_component,
    check_driving_protocol,
    check_energy_term,
    check_friction_law,
    check_pair_term,
    check_stopgo_detector,
)

__all__ = [
    "check_bot_interaction",
    "check_component",
    "check_driving_protocol",
    "check_energy_term",
    "check_friction_law",
    "check_pair_term",
    "check_stopgo_detector",
    "registered",
]
