"""MJCF scene files, installed as package data of ``jugglerl_envs.assets``."""
