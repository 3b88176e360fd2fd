"""softcell beyond: the variants run side by side and their comparison."""

import json

import numpy as np
import pytest

from softcell.model.configuration import RunConfig
from softcell.paper.reproduce import Design, VideoDesign
from softcell.studies.friction_and_arena import VARIANTS, beyond
from softcell.studies.variants import Variant

TINY = Design(
    "tiny",
    radii=(4.0, 12.0),
    realizations=1,
    duration=20.0,
    discard=5.0,
    free_bot_realizations=1,
    video=VideoDesign(radius=12.0, span=3.0),
)


def test_a_variant_changes_only_its_own_components_and_parameters():
    """Every variant is the base design with its own components and parameters over the
    defaults, and each names a component and parameters that exist (a misspelt one would be
    ignored by the study, not refused)."""
    from softcell.components.registry import default_registry
    from softcell.model.configuration import DEFAULT_COMPONENTS

    registry = default_registry()
    assert len({v.name for v in VARIANTS}) == len(VARIANTS)
    for variant in VARIANTS:
        design = variant.design(TINY)
        assert (design.radii, design.duration, design.video) == (
            TINY.radii,
            TINY.duration,
            TINY.video,
        )
        assert design.components == {**DEFAULT_COMPONENTS, **variant.components}
        assert design.parameters == {**TINY.parameters, **variant.parameters}
        config = RunConfig(parameters=design.parameters, components=design.components)
        config.check_components(registry)
        registry.parameters(design.parameters)  # every name declared, every value allowed


@pytest.mark.slow
def test_beyond_compares_the_variants_on_common_random_numbers(tmp_path):
    variants = (
        VARIANTS[0],
        Variant(
            "coulomb_0",
            "coulomb, f_s = 0",
            {"friction_law": "coulomb"},
            {"membrane_static_friction": 0.0},
        ),
        VARIANTS[4],
    )
    report = beyond(
        tmp_path, seed=3, workers=1, variants=variants, base=TINY, progress=False, log=None
    )
    text = report.read_text()
    assert "| finding |" in text and "coulomb, f_s = 0" in text
    assert (tmp_path / "figures" / "friction.png").exists()
    assert (tmp_path / "figures" / "arena.png").exists()
    results = json.loads((tmp_path / "beyond.json").read_text())
    # f_s = 0 is the viscous law to rounding, and both ran on the same random numbers (the
    # adaptive steps may part at the tolerance, ~1e-5 cm, so compare at that level)
    viscous, zero = results["viscous"], results["coulomb_0"]
    assert np.allclose(viscous["ipr_mean"], zero["ipr_mean"], rtol=1e-5)
    # the free bot of the arena variant ran inside the walls; the others on the open floor
    assert results["arena"]["free_renewal_d"] == pytest.approx(viscous["free_renewal_d"])
