"""Integrators: rodas4 (the default, an adaptive Rosenbrock method) and the paper's explicit
Euler scheme, each a built-in component with the templates of its compiled loops beside it."""
