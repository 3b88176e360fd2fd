"""A plugin with a misspelt hook name, which must fail loudly."""

from softcell import hookimpl


@hookimpl
def softcell_energy_term():
    return []
