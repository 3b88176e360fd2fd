"""Parameters, the plugin contracts and registry, the engine, ensembles and analysis."""
