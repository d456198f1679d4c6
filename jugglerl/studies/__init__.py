"""The simulations of the one-off studies in ``scripts/studies/``."""
