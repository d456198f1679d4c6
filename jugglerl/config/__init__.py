"""Hydra configs and the package: envs built from a config (``envs``), and command lines checked
against the configs before Hydra composes them (``command_line``)."""
