"""A study: model variants of one design, run side by side from one root seed.

Each :class:`Variant` is the base design with some components and parameters changed; each
runs into its own folder by :func:`softcell.workflows.reproduce.reproduce` (resumable, with
its own report), from the same root seed, so that the variants share their random numbers
and their differences are the model's, not noise. ``softcell beyond`` and ``softcell study
sensitivity`` are studies; this module holds what they share.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from softcell.core.runconfig import DEFAULT_COMPONENTS
from softcell.workflows.reproduce import QUICK, Design, reproduce


@dataclass(frozen=True)
class Variant:
    """One model variant of a study: components and parameters over the quick design's.

    ``name`` is its folder, ``label`` its legend; ``unknown`` names what it varies (the
    sensitivity study groups its variants by it; empty for the reference). Parameter values
    are in the units of ``softcell params``.
    """

    name: str
    label: str
    components: dict[str, Any] = field(default_factory=dict)
    parameters: dict[str, Any] = field(default_factory=dict)
    unknown: str = ""

    def design(self, base: Design = QUICK) -> Design:
        """``base`` with this variant's components (over the defaults) and parameters."""
        return replace(
            base,
            name=f"{base.name}-{self.name}",
            components={**DEFAULT_COMPONENTS, **self.components},
            parameters={**base.parameters, **self.parameters},
        )


def run_variants(
    out: Path,
    variants: tuple[Variant, ...],
    base: Design,
    *,
    seed: int,
    workers: int | None,
    overwrite: bool,
    progress: bool,
    log: Callable[[str], None] | None,
) -> None:
    """Reproduce each variant of ``base`` into ``out/<variant>`` from one root seed; a
    variant that finished there (same design, seed and version) is kept as it is."""
    from softcell.workflows.reproduce import finished

    say = log or (lambda _: None)
    for i, variant in enumerate(variants):
        design, folder = variant.design(base), out / variant.name
        if not overwrite and finished(folder, design, seed):
            say(f"variant {i + 1}/{len(variants)}: {variant.label} (finished, kept)")
            continue
        say(f"variant {i + 1}/{len(variants)}: {variant.label}")
        reproduce(
            folder,
            design,
            seed=seed,
            workers=workers,
            overwrite=overwrite,
            progress=progress,
            log=log,
        )
