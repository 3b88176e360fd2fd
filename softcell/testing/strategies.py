"""Hypothesis strategies for softcell objects, for our tests and for plugin authors' tests.

Requires the ``test`` extra (hypothesis).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from softcell.model.parameters import MODEL_PARAMETERS, Parameters, ParameterSpec
from softcell.schema import simulation_dataset

_finite = {"allow_nan": False, "allow_infinity": False}


@st.composite
def valid_parameter_values(draw: st.DrawFn) -> dict[str, Any]:
    """Parameter overrides that satisfy every rule of docs/model.md §2."""
    semi_major = draw(st.floats(0.5, 5.0, **_finite))
    nodes = draw(st.sampled_from([64, 128, 256, 512, 1024, 2048]))
    cutoff = draw(st.integers(2, nodes // 2 - 1))
    phase_min = draw(st.floats(0.01, 2.0, **_finite))
    early = draw(st.floats(1e-4, 1.0, **_finite))
    return {
        "radius": semi_major * draw(st.floats(1.01, 5.0, **_finite)),
        "bot_semi_major": semi_major,
        "bot_semi_minor": semi_major * draw(st.floats(0.1, 1.0, **_finite)),
        "nodes": nodes,
        "cutoff": cutoff,
        "stored_nodes": 2 * cutoff + draw(st.integers(1, 100)),
        "phase_min": phase_min,
        "phase_max": phase_min * draw(st.floats(1.0, 5.0, **_finite)),
        "sample_every": early,
        "sample_every_late": early * draw(st.floats(1.0, 20.0, **_finite)),
        "sample_switch": draw(st.floats(0.0, 1e3, **_finite)),
        "pivot_offset": draw(st.floats(0.0, 2.0, **_finite)),
        "pivot_side": draw(st.sampled_from(["inner", "fixed"])),
        "tension": draw(st.floats(1e-4, 10.0, **_finite)),
        "dt": draw(st.floats(1e-8, 1e-3, **_finite)),
    }


def _bad_number(spec: ParameterSpec) -> st.SearchStrategy[Any]:
    bad: list[st.SearchStrategy[Any]] = [
        st.just(math.nan),
        st.just(math.inf),
        st.just(-math.inf),
        st.just(True),
        st.text(max_size=3).filter(lambda s: not _is_number(s)),
    ]
    if spec.minimum is not None:
        below = st.floats(
            spec.minimum - 1e6, spec.minimum, exclude_max=spec.minimum_inclusive, **_finite
        )
        bad.append(below.map(int) if spec.kind is int else below)
    if spec.power_of_two:
        bad.append(st.integers(9, 10**6).filter(lambda n: n & (n - 1) != 0))
    if spec.kind is int:
        bad.append(st.floats(1.5, 100.5).filter(lambda v: not float(v).is_integer()))
    return st.one_of(bad)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


@st.composite
def invalid_parameter_values(draw: st.DrawFn) -> tuple[dict[str, Any], str]:
    """A parameter set that breaks exactly one rule, and the name the error must carry."""
    values = draw(valid_parameter_values())
    rule = draw(
        st.sampled_from(
            ["range", "radius", "semi_minor", "cutoff", "stored_nodes", "phase", "sampling"]
        )
    )
    if rule == "range":
        name = draw(st.sampled_from(sorted(MODEL_PARAMETERS)))
        spec = MODEL_PARAMETERS[name]
        if spec.kind is str:
            values[name] = draw(st.text(max_size=8).filter(lambda s: s not in spec.choices))
        else:
            values[name] = draw(_bad_number(spec))
        return values, name
    if rule == "radius":
        values["radius"] = values["bot_semi_major"] * draw(st.floats(0.01, 1.0, **_finite))
        return values, "radius"
    if rule == "semi_minor":
        values["bot_semi_minor"] = values["bot_semi_major"] * draw(st.floats(1.001, 3.0))
        return values, "bot_semi_minor"
    if rule == "cutoff":
        values["cutoff"] = draw(st.integers(values["nodes"] // 2, values["nodes"] * 2))
        values["stored_nodes"] = 2 * values["cutoff"] + 1
        return values, "cutoff"
    if rule == "stored_nodes":
        values["stored_nodes"] = draw(st.integers(1, 2 * values["cutoff"]))
        return values, "stored_nodes"
    if rule == "phase":
        values["phase_min"] = values["phase_max"] * draw(st.floats(1.001, 10.0))
        return values, "phase_min"
    values["sample_every_late"] = values["sample_every"] * draw(st.floats(0.01, 0.999))
    return values, "sample_every_late"


@st.composite
def simulation_datasets(
    draw: st.DrawFn, max_realizations: int = 3, max_times: int = 12, max_nodes: int = 40
) -> Any:
    """Small Datasets that follow the simulation schema, values including NaN."""
    n_real = draw(st.integers(1, max_realizations))
    n_time = draw(st.integers(1, max_times))
    n_node = draw(st.integers(1, max_nodes))
    steps = draw(hnp.arrays(np.float64, n_time, elements=st.floats(1e-3, 10.0, **_finite)))
    time = np.cumsum(steps) - steps[0]
    floats = st.floats(-1e4, 1e4, width=64) | st.just(math.nan)

    def field(*shape: int) -> np.ndarray:
        return draw(hnp.arrays(np.float64, shape, elements=floats))

    values = draw(valid_parameter_values())
    return simulation_dataset(
        time,
        np.arange(n_real) + draw(st.integers(0, 1000)),
        membrane_x=field(n_real, n_time, n_node),
        membrane_y=field(n_real, n_time, n_node),
        bot_x=field(n_real, n_time),
        bot_y=field(n_real, n_time),
        bot_angle=field(n_real, n_time),
        bot_phase=draw(hnp.arrays(np.int8, (n_real, n_time), elements=st.sampled_from([-1, 0, 1]))),
        parameters=Parameters(values),
        seed=draw(st.integers(0, 2**63 - 1)),
        components={"integrator": draw(st.sampled_from(["explicit_euler", "x"]))},
    )
