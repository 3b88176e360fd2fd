"""Studies beyond the paper: model variants or grids of one design, run side by side from one
root seed, each with its summary, figures and page."""
