"""Layer 2: touches no file and no screen. The schema, parameters, the plugin contracts and
registry, the engine, one realization, the tracker (image -> geometry) and the analysis."""
