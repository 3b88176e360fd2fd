"""Built-in components. Each module is a plugin registered through the same hooks as a
third-party distribution (see :data:`softcell.components.registry.BUILTIN_PLUGINS`)."""
