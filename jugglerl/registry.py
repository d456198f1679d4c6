"""The plug-in registry (``Registry``), shared with the env package's rewards."""

from jugglerl_envs.registry import Registry

__all__ = ["Registry"]
