"""The map between normalised actions in [-1, 1] and servo setpoints in radians.

Actions map linearly onto the control ranges of the actuated joints' position servos, which the
scene's XML fixes (no env argument changes them), so the map needs no env: policies, actors and
exploration modules use these functions directly. An action's length says which servos it
drives: 3 (pan, lift, elbow) or 4 (and ``wrist_1``, whose range is ±2π rad).
"""

from __future__ import annotations

from functools import lru_cache

import mujoco
import numpy as np

from jugglerl_envs import scene


@lru_cache(maxsize=2)
def _centre_and_half_range(servos: int) -> tuple[np.ndarray, np.ndarray]:
    if servos not in (len(scene.ACTUATED_JOINTS), len(scene.ACTUATED_JOINTS_WITH_WRIST_1)):
        raise ValueError(f"an action drives 3 or 4 servos, not {servos}")
    model = mujoco.MjModel.from_xml_path(scene.scene_path())
    ranges = model.actuator_ctrlrange[:servos]
    return ranges.mean(axis=1), (ranges[:, 1] - ranges[:, 0]) / 2


def action_to_ctrl(action: np.ndarray) -> np.ndarray:
    """Servo setpoints (rad) for a normalised action in [-1, 1] (clipped)."""
    centre, half_range = _centre_and_half_range(np.shape(action)[-1])
    clipped = np.minimum(np.maximum(action, -1.0), 1.0)  # np.clip is slow on tiny arrays
    return centre + clipped * half_range


def ctrl_to_action(ctrl: np.ndarray) -> np.ndarray:
    """Normalised action (float32) for servo setpoints (rad); inverse of ``action_to_ctrl``."""
    centre, half_range = _centre_and_half_range(np.shape(ctrl)[-1])
    return ((np.asarray(ctrl) - centre) / half_range).astype(np.float32)
