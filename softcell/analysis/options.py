"""The options of an analysis, declared like model parameters: a default, a unit, a range.

They are validated with the same error as parameters (naming the option, its value, the
allowed range and the unit), offered as ``softcell analyze`` flags, and stored in the
analysis file (``softcell_analysis_options``) so that any analysis can be redone.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from typing import Any

from softcell.analysis.stopgo import THRESHOLD
from softcell.errors import ConfigError
from softcell.model.parameters import ParameterSpec, suggest

ANALYSIS_OPTIONS: dict[str, ParameterSpec] = {
    s.name: s
    for s in (
        ParameterSpec(
            "discard",
            15.0,
            "s",
            "initial time left out of every statistic",
            minimum=0.0,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "short_lag_max",
            1.0,
            "s",
            "lags below this come from the finest sampling segment only",
            minimum=0.0,
        ),
        ParameterSpec(
            "msd_record",
            "fine",
            "1",
            "where the bodies' MSD comes from: 'fine', the bodies' fine record over the whole "
            "run where the file has one (otherwise as 'sampled', with a warning), or 'sampled', "
            "the samples of the time axis (lags below short_lag_max from the finest segment)",
            kind=str,
            choices=("fine", "sampled"),
        ),
        ParameterSpec(
            "lags_per_decade",
            20,
            "1",
            "MSD lags per decade (log-spaced)",
            kind=int,
            minimum=1,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "max_lag_fraction",
            0.5,
            "1",
            "longest MSD lag as a fraction of the record",
            minimum=0.0,
            maximum=1.0,
        ),
        ParameterSpec(
            "correlation_max_lag",
            10.0,
            "s",
            "longest lag of the velocity autocorrelation",
            minimum=0.0,
        ),
        ParameterSpec(
            "ballistic_window",
            0.1,
            "1",
            "ballistic fit over lags <= this times the mean go time",
            minimum=0.0,
        ),
        ParameterSpec(
            "diffusive_window",
            10.0,
            "1",
            "diffusive fit over lags >= this times the mean go time",
            minimum=0.0,
        ),
        ParameterSpec(
            "confined_side", 100.0, "cm", "side L of the confined-square MSD formula", minimum=0.0
        ),
        ParameterSpec(
            "detector",
            None,
            "1",
            "stop/go detector, a plugin name (default: the input's, else threshold)",
            kind=str,
        ),
        ParameterSpec(
            "stopgo_segments",
            "all",
            "1",
            "sampling segments whose complete phases enter the stop/go statistics: "
            "'all', or only the 'finest' (a coarse interval misses short phases)",
            kind=str,
            choices=("all", "finest"),
        ),
        ParameterSpec(
            "stopgo_record",
            "fine",
            "1",
            "where the stop/go phases come from: 'fine', the bodies' fine record over the "
            "whole run where the file has one (one sampling interval: the same cell gives the "
            "same durations whatever the sampling design), or 'sampled', the samples of the "
            "time axis (segment by segment, see stopgo_segments)",
            kind=str,
            choices=("fine", "sampled"),
        ),
        ParameterSpec(
            "resamples",
            1000,
            "1",
            "bootstrap resamples of the realizations behind every error",
            kind=int,
            minimum=2,
            minimum_inclusive=True,
        ),
        dataclasses.replace(
            THRESHOLD,
            default=None,
            long_name=(
                "stop/go speed threshold (default: 0.3 for tracked videos, the detector's "
                "0.03 for simulations)"
            ),
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "threshold_shift",
            0.1,
            "cm s-1",
            "the threshold is also moved by -/+ this to show how the means move",
            minimum=0.0,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "coupled_below",
            0.35,
            "1",
            "coupled regime: mean bot-cell GC distance below this times R",
            minimum=0.0,
        ),
        ParameterSpec(
            "decoupled_above",
            0.5,
            "1",
            "decoupled regime: mean bot-cell GC distance above this times R",
            minimum=0.0,
        ),
    )
}


def validated(
    values: Mapping[str, Any] | None, specs: Mapping[str, ParameterSpec], what: str
) -> dict[str, Any]:
    """``specs``' defaults updated with ``values`` (None values are ignored), each checked.

    Raises
    ------
    ConfigError
        For a name not in ``specs`` (``what`` names the kind of option in the message).
    ParameterError
        For a value outside its range (names the option, value, range and unit).
    """
    given = {k: v for k, v in (values or {}).items() if v is not None}
    for name in given:
        if name not in specs:
            raise ConfigError(f"unknown {what} {name!r}{suggest(name, specs)}")
    out: dict[str, Any] = {}
    for name, spec in specs.items():
        if name in given:
            out[name] = spec.coerce(given[name])
            spec.check(out[name])
        else:
            out[name] = spec.default
    return out


def analysis_options(values: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Validated options: defaults updated with ``values`` (None values are ignored).

    Raises
    ------
    ConfigError
        For an unknown option name.
    ParameterError
        For a value outside its range (names the option, value, range and unit).
    """
    out = validated(values, ANALYSIS_OPTIONS, "analysis option")
    if out["coupled_below"] > out["decoupled_above"]:
        from softcell.errors import ParameterError

        raise ParameterError(
            "coupled_below",
            out["coupled_below"],
            f"must be <= decoupled_above = {out['decoupled_above']:g}",
            "1",
        )
    return out


def options_attrs(options: Mapping[str, Any]) -> dict[str, str]:
    """File attributes of the options: JSON values and units."""
    return {
        "softcell_analysis_options": json.dumps(dict(options), sort_keys=True),
        "softcell_analysis_option_units": json.dumps(
            {k: ANALYSIS_OPTIONS[k].unit for k in options}, sort_keys=True
        ),
    }
