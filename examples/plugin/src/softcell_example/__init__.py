"""softcell-example: one softcell component of each kind, registered through entry points."""

__version__ = "1.0.0"
