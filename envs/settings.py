"""``EnvSettings``: the juggling env's keyword arguments, checked, one value per env.

Every argument of ``JuggleEnv`` is listed once in ``ARGUMENTS`` with its default and its check.
``JuggleBatch`` takes the same arguments, and each may also be a sequence of one value per env
(``reset_noise=[0.0, 0.01, ...]``), so one batch holds nominal and perturbed envs side by side;
the arguments that shape the batch's arrays (``SHARED``) take one value for all envs. A bad value
raises ``ValueError`` naming the argument (``reset_noise[3]=0.9 is out of range: ...``); an
unknown one, ``TypeError``, as Python does.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from jugglerl_envs import scene
from jugglerl_envs.validation import check_number, check_vector

MAX_RESET_NOISE = 0.05  # m: largest start offset of the ball (it must start above the cup)
PAPER_HOME = (0.0, -1.5708, 2.15)  # rad: the paper preset (configs/env/paper.yaml)
PAPER_WRIST = (-2.0, 1.5708, 0.0)


def _number(low: float, high: float, **options) -> Callable[[str, Any], float]:
    return lambda key, value: check_number(key, value, low, high, **options)


def _angles(key: str, value: Any) -> tuple[float, ...]:
    return check_vector(key, value, 3, -2 * math.pi, 2 * math.pi)


def _optional_speed(key: str, value: Any) -> float | None:
    return None if value is None else check_number(key, value, 0.0, 100.0, low_open=True)


def _boolean(key: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{key}={value!r} is not valid: expected a bool")
    return bool(value)


def _name(key: str, value: Any) -> str:
    if not isinstance(value, str):
        raise ValueError(f"{key}={value!r} is not valid: expected a name")
    return value


@dataclass(frozen=True)
class Argument:
    default: Any
    check: Callable[[str, Any], Any]
    #: True for values that are themselves sequences (a pose): a per-env value is a sequence of them
    vector: bool = False


#: Every env argument: its default (the paper preset) and its check.
ARGUMENTS: dict[str, Argument] = {
    "gravity": Argument(-2.0, _number(-50.0, 0.0)),
    "duration": Argument(120.0, _number(0.0, 1e6, low_open=True)),
    "threshold": Argument(1.0, _number(0.0, 10.0, low_open=True)),
    "reward": Argument("throws", _name),
    "frame_skip": Argument(10, _number(1, 1000, integer=True)),
    "timestep": Argument(0.002, _number(0.0, 0.01, low_open=True)),
    "ball_radius": Argument(0.035, _number(0.01, 0.09)),
    "ball_mass": Argument(0.1, _number(0.0, 10.0, low_open=True)),
    "reset_noise": Argument(0.0, _number(0.0, MAX_RESET_NOISE)),
    "joint_speed_limit": Argument(None, _optional_speed),
    "servo_gain": Argument(1.0, _number(0.0, 10.0, low_open=True)),
    "kick_rate": Argument(0.0, _number(0.0, 100.0)),
    "kick_speed": Argument(0.0, _number(0.0, 10.0)),
    "action_noise": Argument(0.0, _number(0.0, 1.0)),
    "action_noise_correlation": Argument(0.0, _number(0.0, 100.0)),
    "ball_noise": Argument(0.0, _number(0.0, 0.1)),
    "ball_latency": Argument(0, _number(0, 50, integer=True)),
    "drop_height": Argument(0.5, _number(0.0, 2.0)),
    "balls": Argument(1, _number(1, scene.MAX_BALLS, integer=True)),
    "ball_spacing": Argument(2.0, _number(0.0, 10.0)),
    "home": Argument(PAPER_HOME, _angles, vector=True),
    "wrist_angles": Argument(PAPER_WRIST, _angles, vector=True),
    "wrist_1_actuated": Argument(False, _boolean),
}
#: Arguments that shape the batch's arrays or its reward: one value for every env of a batch.
SHARED = ("reward", "frame_skip", "balls", "wrist_1_actuated")
#: Arguments compiled into the physics model: envs with equal values share one ``MjModel``.
MODEL_KEYS = ("gravity", "timestep", "ball_radius", "ball_mass", "servo_gain")


class EnvSettings:
    """The checked arguments of ``num_envs`` envs: ``settings.reset_noise`` is an array of one
    value per env (``[num_envs, 3]`` for poses, an object array for ``joint_speed_limit``, which
    may be ``None``); the ``SHARED`` ones are plain values. ``settings.env(i)`` gives env ``i``'s
    arguments as keywords of ``JuggleEnv``."""

    def __init__(self, num_envs: int, **arguments: Any):
        unknown = sorted(set(arguments) - set(ARGUMENTS))
        if unknown:  # Python's own words for it, which callers such as TorchRL's GymEnv expect
            raise TypeError(
                f"got an unexpected keyword argument '{unknown[0]}'; the env's arguments are"
                f" {', '.join(ARGUMENTS)}"
            )
        self.num_envs = num_envs
        for key, argument in ARGUMENTS.items():
            values = _per_env(key, arguments.get(key, argument.default), num_envs, argument)
            if key in SHARED:
                if any(value != values[0] for value in values):
                    raise ValueError(f"{key}={values!r}: one value for every env of a batch")
                setattr(self, key, values[0])
            else:
                dtype = object if key == "joint_speed_limit" else None
                setattr(self, key, np.array(values, dtype=dtype))

    def env(self, index: int) -> dict[str, Any]:
        """Env ``index``'s arguments, as ``JuggleEnv`` keywords."""
        found = {}
        for key, argument in ARGUMENTS.items():
            value = getattr(self, key)
            if key not in SHARED:
                value = value[index]
                value = tuple(value.tolist()) if argument.vector else _plain(value)
            found[key] = value
        return found

    def model_key(self, index: int) -> tuple:
        """What env ``index``'s physics model is compiled from."""
        arguments = self.env(index)
        return tuple(arguments[key] for key in (*MODEL_KEYS, "balls"))


def _plain(value: Any) -> Any:
    """A NumPy scalar as the Python number it holds."""
    return value.item() if isinstance(value, np.generic) else value


def _per_env(key: str, value: Any, num_envs: int, argument: Argument) -> list:
    """``value`` checked, as a list of one value per env."""
    if _is_per_env(value, argument):
        values = list(value)
        if len(values) != num_envs:
            raise ValueError(f"{key}: {len(values)} values for a batch of {num_envs} envs")
        return [argument.check(f"{key}[{index}]", item) for index, item in enumerate(values)]
    return [argument.check(key, value)] * num_envs


def _is_per_env(value: Any, argument: Argument) -> bool:
    if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, np.ndarray)):
        return False
    if not argument.vector:
        return True
    return len(value) > 0 and isinstance(value[0], (Sequence, np.ndarray))
