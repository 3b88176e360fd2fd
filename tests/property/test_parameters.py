"""Parameter validation: the rules of docs/model.md §2 on generated parameter sets."""

import math

import pytest
from hypothesis import given

from softcell.errors import ConfigError, ParameterError
from softcell.model.parameters import MODEL_PARAMETERS, Parameters, expand_sweep
from softcell.testing.strategies import invalid_parameter_values, valid_parameter_values


@given(valid_parameter_values())
def test_valid_sets_pass_and_keep_their_values(values):
    params = Parameters(values)
    for name, value in values.items():
        assert params[name] == value
    assert set(params) == set(MODEL_PARAMETERS)


@given(invalid_parameter_values())
def test_each_broken_rule_names_its_parameter(case):
    values, name = case
    with pytest.raises(ParameterError) as info:
        Parameters(values)
    assert info.value.name == name
    message = str(info.value)
    assert name in message and "must be" in message
    unit = MODEL_PARAMETERS[name].unit
    if unit != "1":
        assert unit in message


def test_spec_table_defaults():
    p = Parameters()
    assert (p.radius, p.nodes, p.cutoff, p.stored_nodes) == (4.0, 1024, 16, 64)
    assert p.specs["bending_stiffness"].unit == "N cm2"
    assert p.membrane_length == pytest.approx(2 * math.pi * 4.0)
    assert p.duration == 900.0
    assert Parameters({"radius": 9}).duration == 900.0
    assert Parameters({"radius": 10}).duration == 1800.0
    assert Parameters({"radius": 12, "duration": 5}).duration == 5.0


def test_zero_pivot_offset_is_allowed_but_zero_constants_are_not():
    assert Parameters({"pivot_offset": 0}).pivot_offset == 0.0
    for name in ("bending_stiffness", "tension", "drive_force", "contact_length"):
        with pytest.raises(ParameterError, match=name):
            Parameters({name: 0})


def test_unknown_parameter_suggests_the_right_one():
    with pytest.raises(ConfigError, match="did you mean 'radius'"):
        Parameters({"raduis": 5})


def test_replace_recomputes_derived_defaults():
    p = Parameters({"radius": 12})
    assert p.replace(radius=5).duration == 900.0
    assert p.replace(duration=3).radius == 12.0


def test_attrs_round_trip():
    p = Parameters({"radius": 7.5, "cutoff": 12, "pivot_side": "fixed"})
    assert Parameters.from_attrs(p.to_attrs()) == p


def test_sweep_expands_row_major_and_validates_every_point():
    points = expand_sweep({"radius": [4, 8], "tension": [0.01, 0.02, 0.03]})
    assert [(s["radius"], s["tension"]) for s, _ in points] == [
        (4.0, 0.01),
        (4.0, 0.02),
        (4.0, 0.03),
        (8.0, 0.01),
        (8.0, 0.02),
        (8.0, 0.03),
    ]
    with pytest.raises(ParameterError, match="radius"):
        expand_sweep({"radius": [4, 2]})
