"""The model: every parameter with its default, unit and range; a run's configuration (values,
possibly swept, and the chosen components); where fixed obstacles stand; where many cells
start; what this machine allows."""
