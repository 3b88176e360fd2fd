"""Fitting the model's unknowns to data: priors over parameters, the summary statistics that
data and simulations are compared by, and (to come) the design of simulations and the
inference that turns them into a posterior.
"""
