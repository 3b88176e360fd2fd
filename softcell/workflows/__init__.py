"""Orchestration: ensembles with files, checkpoints and dask; the whole paper; the experimental
pipeline; findings and the report."""
