"""``SceneMeasurements``: what the juggling env reads off its MuJoCo state after a step.

The ball's height, position and contacts, the cup's position and velocity, whether the ball is in
the cup, and whether the physics went bad. A mixin of ``JuggleEnv`` (it reads ``self.model``,
``self.data`` and ``self.actuated_joints``); ``_cache_ids`` looks the scene's ids up once.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from jugglerl_envs import scene


class SceneMeasurements:
    def _cache_ids(self) -> None:
        m = self.model
        self._arm_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in scene.ARM_JOINTS])
        self._arm_qvel = np.array([m.jnt_dofadr[m.joint(j).id] for j in self.actuated_joints])
        ball_joint = m.body(scene.BALL_BODY).jntadr[0]
        self._ball_qpos = m.jnt_qposadr[ball_joint]
        self._ball_qvel = m.jnt_dofadr[ball_joint]
        self._cup_site = m.site(scene.CUP_SITE).id
        self._ball_geom = m.geom(scene.BALL_GEOM).id
        self._contact_sensor = m.sensor_adr[m.sensor(scene.BALL_CONTACT_SENSOR).id]
        arm_root = m.body(scene.ARM_ROOT_BODY).id
        arm_bodies = [b for b in range(m.nbody) if self._has_ancestor(b, arm_root)]
        self._arm_geoms = np.flatnonzero(np.isin(m.geom_bodyid, arm_bodies))
        self._site_velocity = np.zeros(6)

    def _has_ancestor(self, body: int, ancestor: int) -> bool:
        while body != ancestor and body != 0:
            body = self.model.body_parentid[body]
        return body == ancestor

    def _check_physics(self) -> str:
        """Name of the first MuJoCo warning raised this episode, or of a NaN state; "" if none."""
        counts = self.data.warning.number
        if counts.any():
            return f"{mujoco.mjtWarning(np.flatnonzero(counts)[0]).name} at t={self.data.time:.3f}s"
        if not math.isfinite(self.data.qpos.sum() + self.data.qvel.sum()):  # NaN/inf anywhere
            return f"non-finite state at t={self.data.time:.3f}s"
        return ""

    def _ball_height(self) -> float:
        return float(self.data.qpos[self._ball_qpos + 2])

    def _ball_in_flight(self) -> bool:
        return self.data.sensordata[self._contact_sensor] == 0

    def ball_in_cup_frame(self) -> tuple[float, float]:
        """Ball centre in the cup frame (m): (distance from the cone axis, height above throat)."""
        offset = (
            self.data.qpos[self._ball_qpos : self._ball_qpos + 3]
            - self.data.site_xpos[self._cup_site]
        )
        local = self.data.site_xmat[self._cup_site].reshape(3, 3).T @ offset
        return math.hypot(local[0], local[1]), float(local[2])

    def _measure_ball_in_cup(self) -> None:
        """Set ``_in_cup`` (centre inside the cone, below the rim) and ``_clear_of_cup``.

        Clear means more than a ball radius outside the cone: a ball sloshing up to the rim is
        neither caught again nor counted as lost.
        """
        radial, height = self.ball_in_cup_frame()
        self._in_cup = 0.0 <= height <= scene.CUP_DEPTH and radial <= scene.CUP_TOP_RADIUS
        margin = self.ball_radius
        self._clear_of_cup = (
            height > scene.CUP_DEPTH + margin or radial > scene.CUP_TOP_RADIUS + margin
        )

    def _cup_velocity(self) -> np.ndarray:
        mujoco.mj_objectVelocity(
            self.model, self.data, mujoco.mjtObj.mjOBJ_SITE, self._cup_site, self._site_velocity, 0
        )
        return self._site_velocity[3:]

    def ball_arm_contacts(self) -> int:
        """Contacts between the ball and the arm (links and cup plates) after the last step."""
        contacts = self.data.contact
        geoms = np.stack([contacts.geom1, contacts.geom2], axis=1)
        with_ball = (geoms == self._ball_geom).any(axis=1)
        other = np.where(geoms[:, 0] == self._ball_geom, geoms[:, 1], geoms[:, 0])
        return int(np.isin(other[with_ball], self._arm_geoms).sum())

    def ball_position(self) -> np.ndarray:
        """The ball's centre (m, world frame)."""
        return self.data.qpos[self._ball_qpos : self._ball_qpos + 3]

    def cup_position(self) -> np.ndarray:
        """The cup's throat (site ``cup``, m, world frame), from the last physics step."""
        return self.data.site_xpos[self._cup_site]
