"""``CupIK``: the pan, lift and elbow angles that put the cup's throat at a point.

The wrist stays locked at the env's ``wrist_angles``, so three joints place three coordinates and
the cup tilts however those joints leave it (a few degrees across the catch poses of
``earth_juggler``). Damped least squares on MuJoCo's site Jacobian of the scene's own kinematics:
the scene is built from the UR5e's DH figures plus an offset wrist and cup, for which a closed
form would repeat what MuJoCo already computes. Warm-started from the last solution, it converges
in two or three iterations; steps are capped so that a start near a singular pose cannot throw the
solution across the workspace, and the result is clipped to the servos' control ranges.
"""

from __future__ import annotations

import mujoco
import numpy as np

from jugglerl_envs import scene

#: Largest change of any joint angle in one iteration (rad).
MAX_STEP = 0.3
#: Damping of the least-squares step (m²): keeps steps finite near singular poses.
DAMPING = 1e-4
#: Squared position error (m²) at which the solve stops early.
TOLERANCE = 1e-12


class CupIK:
    """Solves for the throat's position with ``wrist_angles`` (rad) locked."""

    def __init__(self, wrist_angles, iterations: int = 10):
        self.model = mujoco.MjModel.from_xml_path(scene.scene_path())
        self.data = mujoco.MjData(self.model)
        self.iterations = iterations
        arm = len(scene.ACTUATED_JOINTS)
        self._dofs = np.array([self.model.joint(name).dofadr[0] for name in scene.ACTUATED_JOINTS])
        self._qpos = np.array([self.model.joint(name).qposadr[0] for name in scene.ARM_JOINTS])
        self._wrist = np.asarray(wrist_angles, dtype=float)
        self._site = self.model.site(scene.CUP_SITE).id
        self._jacobian = np.zeros((3, self.model.nv))
        self.low, self.high = self.model.actuator_ctrlrange[:arm].T.copy()

    def __reduce__(self):
        """Pickles as its arguments (the model is rebuilt), not as the 1.8 MB model and data:
        policies holding one travel to worker processes and Ray tasks."""
        return CupIK, (tuple(self._wrist), self.iterations)

    def throat(self, joints: np.ndarray) -> np.ndarray:
        """The throat's position (m, world frame) with the actuated joints at ``joints`` (rad)."""
        self.data.qpos[self._qpos] = np.concatenate([joints, self._wrist])
        mujoco.mj_kinematics(self.model, self.data)
        return self.data.site_xpos[self._site].copy()

    def solve(
        self, target: np.ndarray, start: np.ndarray, level: float | None = None
    ) -> np.ndarray:
        """Joint angles (pan, lift, elbow; rad) putting the throat at ``target`` (m), from
        ``start``; the nearest reachable pose when ``target`` is out of reach. With ``level``
        (rad), lift + elbow stays at it, which keeps the cup's tilt, and only the throat's
        horizontal position is placed: its height is wherever that leaves it."""
        joints = np.array(start, dtype=float)
        if level is not None:
            joints[2] = level - joints[1]
        placed = 3 if level is None else 2
        for _ in range(self.iterations):
            error = (target - self.throat(joints))[:placed]
            if error @ error < TOLERANCE:
                break
            mujoco.mj_comPos(self.model, self.data)
            mujoco.mj_jacSite(self.model, self.data, self._jacobian, None, self._site)
            jac = self._jacobian[:placed, self._dofs]
            if level is not None:  # the unknowns: pan and lift, the elbow following the lift
                jac = np.stack([jac[:, 0], jac[:, 1] - jac[:, 2]], axis=1)
            step = np.linalg.solve(jac.T @ jac + DAMPING * np.eye(placed), jac.T @ error)
            step *= min(1.0, MAX_STEP / max(np.abs(step).max(), 1e-12))
            if level is not None:
                step = np.array([step[0], step[1], -step[1]])
            joints = np.clip(joints + step, self.low, self.high)
        return joints
