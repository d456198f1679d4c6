"""Loads the MJCF scene in ``assets/`` and applies the physical parameters an env asks for.

Gravity, timestep, ball radius and ball mass are edited on an ``MjSpec`` before compiling, so that
derived quantities (ball inertia, bounding radii) stay consistent with the new values. A scene of
several balls copies the XML's ball (body ``ball``, its free joint and its contact sensor) as
``ball_1``, ``ball_2``, ... in other colours; balls do not collide with each other (a ball's
``conaffinity`` is 0), only with the arm, the cup and the floor.
"""

from __future__ import annotations

import re
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

BALL_BODY = "ball"
BALL_GEOM = "ball"
CUP_SITE = "cup"
ARM_ROOT_BODY = "base"
BALL_CONTACT_SENSOR = "ball_contact"

#: RGBA of ``ball_1``, ``ball_2``, ... (``ball`` is red in the XML).
EXTRA_BALL_COLOURS = ("0.1 0.3 0.9 1", "0.95 0.75 0.1 1", "0.1 0.7 0.3 1", "0.6 0.2 0.8 1")
#: Most balls a scene holds.
MAX_BALLS = 1 + len(EXTRA_BALL_COLOURS)

#: Inner shape of the cone cup (metres), as drawn in the XML: used to tell "ball in the cup".
CUP_DEPTH = 0.10
CUP_TOP_RADIUS = 0.096


def scene_path() -> str:
    """Path of the scene XML, wherever the package is installed."""
    return str(resources.files("jugglerl_envs.assets").joinpath("juggle.xml"))


def ball_name(ball: int) -> str:
    """Body and geom name of ball ``ball`` (0: the XML's ``ball``)."""
    return BALL_BODY if ball == 0 else f"{BALL_BODY}_{ball}"


def ball_contact_sensor(ball: int) -> str:
    """Name of the contact sensor of ball ``ball``: 1 when it touches anything."""
    return BALL_CONTACT_SENSOR if ball == 0 else f"{ball_name(ball)}_contact"


def load_model(
    gravity: float, timestep: float, ball_radius: float, ball_mass: float, balls: int = 1
) -> mujoco.MjModel:
    """Compile the scene with vertical ``gravity`` (m/s², negative is down) and ``balls`` balls of
    the given radius and mass."""
    with open(scene_path(), encoding="utf-8") as file:
        spec = mujoco.MjSpec.from_string(_with_balls(file.read(), balls))
    spec.option.gravity = [0.0, 0.0, gravity]
    spec.option.timestep = timestep
    for ball in range(balls):
        geom = spec.geom(ball_name(ball))
        geom.size = [ball_radius, 0.0, 0.0]
        geom.mass = ball_mass
    return spec.compile()


def _with_balls(xml: str, balls: int) -> str:
    """The scene XML with ``balls - 1`` copies of its ball body and contact sensor added."""
    body = re.search(r'\n\s*<body name="ball".*?</body>', xml, re.DOTALL).group(0)
    sensor = re.search(r'\n\s*<contact name="ball_contact"[^>]*/>', xml).group(0)
    bodies, sensors = [], []
    for ball in range(1, balls):
        name = ball_name(ball)
        copy = body.replace('name="ball"', f'name="{name}"').replace("ball_joint", f"{name}_joint")
        bodies.append(re.sub(r'rgba="[^"]*"', f'rgba="{EXTRA_BALL_COLOURS[ball - 1]}"', copy))
        sensors.append(
            sensor.replace(BALL_CONTACT_SENSOR, ball_contact_sensor(ball)).replace(
                'body1="ball"', f'body1="{name}"'
            )
        )
    xml = xml.replace(body, body + "".join(bodies))
    return xml.replace(sensor, sensor + "".join(sensors))
