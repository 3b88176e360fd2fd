"""Each compiled kernel against its slow twin in ``tests/naive.py``."""

import math

import naive
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from softcell.analysis.msd import msd
from softcell.components.registry import default_registry
from softcell.engine import build_model, circle_modes, force_modes, total_energy
from softcell.engine.kernels.ellipse import signed_distance_local
from softcell.engine.kernels.linalg import lu_factor, lu_solve, lu_workspace
from softcell.engine.kernels.runs import run_lengths
from softcell.model.parameters import Parameters

COARSE = {"cutoff": 4, "nodes": 64}


def perturbed_membrane(radius, seed, pose=(0.0, 0.0, 0.0)):
    params = Parameters({"radius": radius, **COARSE})
    model = build_model(
        params, ["bending", "tension", "contact"], "run_and_tumble", registry=default_registry()
    )
    rng = np.random.default_rng(seed)
    modes = circle_modes(radius + 0.02, model.cutoff)
    modes += 0.03 * (rng.normal(size=modes.size) + 1j * rng.normal(size=modes.size))
    return model, modes, np.array(pose)


@settings(max_examples=5, deadline=None)
@given(st.floats(3.4, 6.0), st.integers(0, 2**16))
def test_energy_and_forces_against_the_naive_formulas(radius, seed):
    # The bot pushed against the membrane, so the contact counts too.
    model, modes, pose = perturbed_membrane(radius, seed, (radius - 3.0, 0.0, 0.0))
    p = model.params
    assert total_energy(model, modes, pose) == pytest.approx(
        naive.energy(modes, model.nodes, p, pose), rel=1e-10
    )
    fhat, _ = force_modes(model, modes, pose)
    twin = naive.force_modes(modes, model.nodes, p, pose)
    scale = np.abs(twin).max()
    assert np.abs(fhat - twin).max() <= 1e-5 * scale


@settings(max_examples=200)
@given(st.floats(-12, 12), st.floats(-12, 12), st.floats(1.0, 4.0), st.floats(0.3, 1.0))
def test_signed_distance_against_a_brute_force_search(px, py, a, ratio):
    b = a * ratio
    rho, nx, ny = signed_distance_local(px, py, a, b)
    assert rho == pytest.approx(naive.signed_distance(px, py, a, b), abs=1e-9)
    assert math.hypot(nx, ny) == pytest.approx(1.0, abs=1e-12)


@settings(max_examples=50)
@given(
    arrays(
        np.float64, st.tuples(st.integers(2, 40), st.integers(1, 3)), elements=st.floats(-100, 100)
    ),
    st.data(),
)
def test_msd_against_the_double_loop(positions, data):
    missing = data.draw(st.lists(st.integers(0, positions.shape[0] - 1), max_size=5))
    positions[missing] = np.nan
    assert np.allclose(msd(positions), naive.msd(positions), rtol=1e-9, atol=1e-9, equal_nan=True)


@settings(max_examples=50)
@given(st.integers(1, 12), st.integers(0, 2**16), st.booleans())
def test_lu_solve_against_gaussian_elimination(n, seed, transposed):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n)) + n * np.eye(n) * rng.uniform(0, 1)
    b = rng.normal(size=n)
    stored = np.ascontiguousarray(a.T) if transposed else a.copy()  # what the workspace expects
    factors, pivots, x = stored, lu_workspace(n, transposed), b.copy()
    assert lu_factor(factors, pivots)
    lu_solve(factors, pivots, x)
    assert np.allclose(x, naive.solve(a, b), rtol=1e-8, atol=1e-8 * np.abs(x).max())


def test_lu_factor_reports_a_singular_matrix():
    a = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 1.0]])  # row 2 = 2 row 1
    assert not lu_factor(a.copy(), lu_workspace(3))
    assert lu_factor(np.eye(3), lu_workspace(3))


@settings(max_examples=200)
@given(st.lists(st.tuples(st.integers(-1, 1), st.integers(0, 2)), max_size=60))
def test_run_lengths_against_the_definition(samples):
    labels = np.array([s[0] for s in samples], dtype=np.int8)
    segment = np.cumsum([s[1] == 2 for s in samples]).astype(np.int64)  # new segments
    start, length, value = run_lengths(labels, segment)
    assert list(zip(start.tolist(), length.tolist(), value.tolist(), strict=True)) == naive.phases(
        labels.tolist(), segment.tolist()
    )
