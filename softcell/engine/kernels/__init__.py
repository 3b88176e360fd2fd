"""Pure compiled kernels on contiguous float64/complex128 arrays: no xarray, no I/O."""
