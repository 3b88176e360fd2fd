"""Layer 3, beside the plugins: everything that touches a file or a screen (TOML, NetCDF,
atomic writes, video capture and rendering, figures)."""
