"""A plugin that fails at import."""

raise ImportError("this fake plugin needs a module that is not installed")
