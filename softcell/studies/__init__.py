"""Studies beyond the paper: model variants or grids of one design, run side by side from one
root seed, each with its summary, figures and page.

The grid studies follow one protocol (:class:`~softcell.studies.protocol.GridStudy`);
:func:`grid_studies` finds them by name, as ``softcell study NAME`` does.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from softcell.studies.protocol import GridStudy


def grid_studies() -> dict[str, GridStudy]:
    """The grid studies by name: ``constriction``, ``crowding`` and ``strategies``."""
    from softcell.studies import constriction, crowding, locomotion

    return {study.name: study for study in (constriction.STUDY, crowding.STUDY, locomotion.STUDY)}
