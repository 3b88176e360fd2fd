"""Running many realizations: the plan of an ensemble, one task per realization with its
checkpoint, resuming a folder, local processes and dask.distributed clusters."""
