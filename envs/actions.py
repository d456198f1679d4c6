"""The map between normalised actions in [-1, 1] and servo setpoints in radians.

Actions map linearly onto the control ranges of the actuated joints' position servos, which the
scene's XML fixes (no env argument changes them), so the map needs no env: policies, actors and
exploration modules use these functions directly.
"""

from __future__ import annotations

from functools import lru_cache

import mujoco
import numpy as np

from jugglerl_envs import scene


@lru_cache(maxsize=1)
def _centre_and_half_range() -> tuple[np.ndarray, np.ndarray]:
    model = mujoco.MjModel.from_xml_path(scene.scene_path())
    ranges = model.actuator_ctrlrange[: len(scene.ACTUATED_JOINTS)]
    return ranges.mean(axis=1), (ranges[:, 1] - ranges[:, 0]) / 2


def action_to_ctrl(action: np.ndarray) -> np.ndarray:
    """Servo setpoints (rad) for a normalised action in [-1, 1] (clipped)."""
    centre, half_range = _centre_and_half_range()
    clipped = np.minimum(np.maximum(action, -1.0), 1.0)  # np.clip is slow on tiny arrays
    return centre + clipped * half_range


def ctrl_to_action(ctrl: np.ndarray) -> np.ndarray:
    """Normalised action (float32) for servo setpoints (rad); inverse of ``action_to_ctrl``."""
    centre, half_range = _centre_and_half_range()
    return ((np.asarray(ctrl) - centre) / half_range).astype(np.float32)
