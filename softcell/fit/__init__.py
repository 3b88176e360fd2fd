"""Fitting the model's unknowns: to data (simulations, or tracked films that the fit's own
simulations are filmed and tracked like), through a space-filling design of simulations, an
emulator of their statistics and MCMC; or to the paper's picture, its findings scored across
a design of the unknowns.
"""
