"""Where many cells live: domains, placements and contact groups, against brute force."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softcell.errors import ParameterError, SoftcellError
from softcell.model.assembly import Domain, contact_groups, place_cells


def _groups_by_brute_force(centres, radii, reach, box):
    """Groups from every pair and, in a periodic box of side ``box``, every one of the nine
    images explicitly (no minimum image), joined by a plain union-find."""
    m = len(centres)
    parent = list(range(m))

    def root(a):
        while parent[a] != a:
            a = parent[a]
        return a

    shifts = [(0.0, 0.0)] if box is None else itertools.product((-box, 0.0, box), repeat=2)
    shifts = list(shifts)
    for i in range(m):
        for j in range(i + 1, m):
            d = min(
                np.hypot(centres[j, 0] + sx - centres[i, 0], centres[j, 1] + sy - centres[i, 1])
                for sx, sy in shifts
            )
            if d < radii[i] + radii[j] + reach:
                parent[root(j)] = root(i)
    roots = [root(i) for i in range(m)]
    names: dict[int, int] = {}
    return np.array([names.setdefault(r, len(names)) for r in roots])


@settings(max_examples=60, deadline=None)
@given(
    m=st.integers(1, 40),
    boundary=st.sampled_from(["open", "walls", "periodic"]),
    reach=st.floats(0.0, 2.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_contact_groups_are_the_brute_force_groups(m, boundary, reach, seed):
    rng = np.random.default_rng(seed)
    box = None if boundary == "open" else 60.0
    centres = (rng.random((m, 2)) - 0.5) * 60.0
    radii = rng.uniform(2.0, 6.0, m)
    labels = contact_groups(centres, radii, reach, Domain(boundary, box))
    periodic_box = box if boundary == "periodic" else None
    expected = _groups_by_brute_force(centres, radii, reach, periodic_box)
    np.testing.assert_array_equal(labels, expected)


def test_a_periodic_box_joins_rings_across_its_edges():
    centres = np.array([[-14.0, 0.0], [14.5, 0.0], [0.0, 0.0]])
    domain = Domain("periodic", 30.0)
    # 1.5 cm apart through the edge, 5 cm of rings between: touching within a reach of 0.5 cm
    assert list(contact_groups(centres, 1.0, 0.5, domain)) == [0, 0, 1]
    assert list(contact_groups(centres, 1.0, 0.5, Domain("walls", 30.0))) == [0, 1, 2]
    with pytest.raises(ParameterError, match=r"box = 8.0 cm .* must be > 10 cm"):
        contact_groups(centres, 2.0, 1.0, Domain("periodic", 8.0))


@settings(max_examples=40, deadline=None)
@given(
    m=st.integers(1, 30),
    boundary=st.sampled_from(["open", "walls", "periodic"]),
    placement=st.sampled_from(["lattice", "random"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_placed_rings_keep_their_gap_from_each_other_and_the_walls(m, boundary, placement, seed):
    radius, gap = 5.0, 1.0
    box = None if boundary == "open" else 2 * (2 * radius + gap) * np.ceil(np.sqrt(m)) + 4
    domain = Domain(boundary, box)
    rng = np.random.default_rng(seed)
    centres = place_cells(m, radius, domain, rng, placement=placement, gap=gap)
    assert centres.shape == (m, 2)
    i, j = np.triu_indices(m, 1)
    d = np.hypot(*domain.displacement(centres[i], centres[j]).T)
    assert d.size == 0 or d.min() >= 2 * radius + gap - 1e-9
    if boundary == "walls":
        assert np.abs(centres).max() <= box / 2 - radius - gap
    again = place_cells(
        m, radius, domain, np.random.default_rng(seed), placement=placement, gap=gap
    )
    np.testing.assert_array_equal(centres, again)  # one seed, one placement


def test_placement_keeps_clear_of_obstacles():
    domain = Domain("walls", 60.0)
    obstacles = "post 0 0 4; wall -30 10 30 10 1"
    centres = place_cells(
        12, 4.0, domain, np.random.default_rng(1), placement="random", obstacles=obstacles
    )
    from softcell.model.obstacle_layout import surface_distances

    assert surface_distances(centres[:, 0], centres[:, 1], obstacles).min() >= 4.0 + 1.0
    with pytest.raises(SoftcellError, match=r"on a lattice: a ring would come within 1 cm of an"):
        place_cells(4, 4.0, domain, np.random.default_rng(1), obstacles=obstacles)


def test_a_placement_that_cannot_fit_says_why():
    with pytest.raises(
        SoftcellError,
        match=r"cannot place 16 rings of radius 5 cm with a gap of 1 cm in a periodic box of "
        r"side 40 cm \(area fraction 0.79\) on a lattice: two rings would come within 1 cm",
    ):
        place_cells(16, 5.0, Domain("periodic", 40.0), np.random.default_rng(0))
    with pytest.raises(SoftcellError, match=r"at random: \d+ placed in 200 draws"):
        place_cells(
            16,
            5.0,
            Domain("walls", 40.0),
            np.random.default_rng(0),
            placement="random",
            tries=200,
        )


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Domain("torus", 10.0), r"boundary = 'torus' .* must be one of open, walls"),
        (
            lambda: Domain("walls"),
            r"box = None cm .* must be > 0 cm and at most 1e\+06 cm for boundary",
        ),
        (lambda: Domain("open", 10.0), r"box = 10.0 cm .* must be unset for the open plane"),
        (lambda: Domain("periodic", float("inf")), r"box = inf cm"),
        (
            lambda: place_cells(0, 5.0, Domain(), np.random.default_rng(0)),
            r"cells = 0 .* integer >= 1",
        ),
        (
            lambda: place_cells(2, 5.0, Domain(), np.random.default_rng(0), placement="hex"),
            r"placement = 'hex'",
        ),
    ],
)
def test_bad_domains_and_placements_are_refused_naming_the_value(make, message):
    with pytest.raises(ParameterError, match=message):
        make()
