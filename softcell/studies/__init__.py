"""Studies beyond the paper: model variants or grids of one design, run side by side from one
root seed, each with its summary, figures and page.

Every study follows one protocol (:class:`~softcell.studies.protocol.Study`): the grid
studies (constriction, crowding, strategies) are
:class:`~softcell.studies.protocol.GridStudy`, the variant studies (sensitivity, beyond)
:class:`~softcell.studies.protocol.VariantStudy`. :func:`studies` finds them by name, as
``softcell study NAME`` does.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from softcell.studies.protocol import Study

#: Each study's name and the module whose ``STUDY`` it is (imported when asked for).
WHERE = {
    "sensitivity": "softcell.studies.sensitivity",
    "beyond": "softcell.studies.friction_and_arena",
    "constriction": "softcell.studies.constriction",
    "crowding": "softcell.studies.crowding",
    "strategies": "softcell.studies.locomotion",
    "bots": "softcell.studies.bots",
}


def studies() -> dict[str, Study]:
    """Every study by name: ``sensitivity``, ``beyond``, ``constriction``, ``crowding``,
    ``strategies`` and ``bots``."""
    return {name: importlib.import_module(module).STUDY for name, module in WHERE.items()}
