"""Loads the MJCF scene in ``assets/`` and applies the physical parameters an env asks for.

Gravity, timestep, ball radius and ball mass are edited on an ``MjSpec`` before compiling, so that
derived quantities (ball inertia, bounding radii) stay consistent with the new values.
"""

from __future__ import annotations

from importlib import resources

import mujoco

ARM_JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
#: The learnable actuators (position servos), in action order: the paper's three.
ACTUATED_JOINTS = ARM_JOINTS[:3]
#: With ``JuggleEnv(wrist_1_actuated=True)``, ``wrist_1_joint`` is a fourth, after them.
ACTUATED_JOINTS_WITH_WRIST_1 = ARM_JOINTS[:4]
WRIST_JOINTS = ARM_JOINTS[3:]

BALL_BODY = "ball"
BALL_GEOM = "ball"
CUP_SITE = "cup"
CUP_BODY = "cup"
ARM_ROOT_BODY = "base"
FLOOR_GEOM = "floor"
BALL_CONTACT_SENSOR = "ball_contact"

#: Inner shape of the cone cup (metres), as drawn in the XML: used to tell "ball in the cup".
CUP_DEPTH = 0.10
CUP_TOP_RADIUS = 0.096


def scene_path() -> str:
    """Path of the scene XML, wherever the package is installed."""
    return str(resources.files("jugglerl_envs.assets").joinpath("juggle.xml"))


def load_model(
    gravity: float, timestep: float, ball_radius: float, ball_mass: float
) -> mujoco.MjModel:
    """Compile the scene with vertical ``gravity`` (m/s², negative is down) and the given ball."""
    spec = mujoco.MjSpec.from_file(scene_path())
    spec.option.gravity = [0.0, 0.0, gravity]
    spec.option.timestep = timestep
    ball = spec.geom(BALL_GEOM)
    ball.size = [ball_radius, 0.0, 0.0]
    ball.mass = ball_mass
    return spec.compile()
