"""Hydra configs and command files, installed as package data of ``jugglerl.configs``."""
