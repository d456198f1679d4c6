"""JuggleRL's Gymnasium environments (installed as ``jugglerl_envs``; needs no torch).

Importing this package registers ``JuggleRL/Juggle-v0``;
``gymnasium.make("jugglerl_envs:JuggleRL/Juggle-v0")`` imports it on demand. ``JuggleBatch`` steps
many of its envs at once (``jugglerl_envs.batch``).
"""

import os
import platform

# Headless machines have no display for MuJoCo's default GLFW backend; EGL renders off-screen.
# Set before MuJoCo is imported, and only when the user has not chosen a backend.
if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
    os.environ["MUJOCO_GL"] = "egl"

#: The values of ``MUJOCO_GL`` MuJoCo's bindings take on this system (any other fails their import).
GL_BACKENDS = {"Linux": ("egl", "osmesa", "glfw", "glx"), "Darwin": ("cgl", "glfw")}.get(
    platform.system(), ("glfw", "wgl")
)
_GL_SWITCHES = ("", "enable", "enabled", "on", "true", "1", "disable", "disabled", "off", "false")
_chosen = os.environ.get("MUJOCO_GL", "")
if _chosen.lower().strip() not in (*GL_BACKENDS, *_GL_SWITCHES, "0"):
    # before MuJoCo's import raises it with a traceback: one line, as every tool's errors
    raise SystemExit(
        f"error: MUJOCO_GL={_chosen} is not a MuJoCo rendering backend here;"
        f" use one of {', '.join(GL_BACKENDS)}, or unset it"
    )

try:
    import mujoco  # noqa: E402, F401  (its import loads the OpenGL backend MUJOCO_GL names)
except Exception as error:  # PyOpenGL fails in many ways on a missing library
    raise SystemExit(
        f"error: MUJOCO_GL={_chosen}: MuJoCo could not load"
        f" this OpenGL backend ({type(error).__name__}: {error}); install its library (OSMesa:"
        f" apt-get install libosmesa6), choose another of {', '.join(GL_BACKENDS)}, or unset it"
    ) from None

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
