"""JuggleRL's Gymnasium environments (installed as ``jugglerl_envs``; needs no torch).

Importing this package registers ``JuggleRL/Juggle-v0``;
``gymnasium.make("jugglerl_envs:JuggleRL/Juggle-v0")`` imports it on demand. ``JuggleBatch`` steps
many of its envs at once (``jugglerl_envs.batch``).
"""

import os

# Headless machines have no display for MuJoCo's default GLFW backend; EGL renders off-screen.
# Set before MuJoCo is imported, and only when the user has not chosen a backend.
if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
    os.environ["MUJOCO_GL"] = "egl"

import gymnasium  # noqa: E402

from jugglerl_envs.batch import JuggleBatch  # noqa: E402
from jugglerl_envs.juggle import JuggleEnv  # noqa: E402

ENV_ID = "JuggleRL/Juggle-v0"

__all__ = ["ENV_ID", "JuggleBatch", "JuggleEnv", "register_envs"]


def register_envs() -> None:
    """Register the env ids with Gymnasium (idempotent)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point="jugglerl_envs.juggle:JuggleEnv")


register_envs()
