"""``SceneMeasurements``: what the juggling env reads off its MuJoCo state after a step.

Each ball's height, position and contacts, the cup's position and velocity, whether a ball is in
the cup, and whether the physics went bad. A mixin of ``JuggleEnv`` (it reads ``self.model``,
``self.data``, ``self.actuated_joints`` and ``self.balls``); ``_cache_ids`` looks the scene's ids
up once. The methods about a ball take its index, ``0`` (the first ball) by default.
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
        joints = [m.body(scene.ball_name(ball)).jntadr[0] for ball in range(self.balls)]
        self._balls_qpos = [int(m.jnt_qposadr[joint]) for joint in joints]
        self._balls_qvel = [int(m.jnt_dofadr[joint]) for joint in joints]
        self._cup_site = m.site(scene.CUP_SITE).id
        self._ball_geom = m.geom(scene.BALL_GEOM).id
        self._contact_sensors = [
            m.sensor_adr[m.sensor(scene.ball_contact_sensor(ball)).id] for ball in range(self.balls)
        ]
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

    def _ball_height(self, ball: int = 0) -> float:
        return float(self.data.qpos[self._balls_qpos[ball] + 2])

    def _ball_in_flight(self, ball: int = 0) -> bool:
        return self.data.sensordata[self._contact_sensors[ball]] == 0

    def ball_in_cup_frame(self, ball: int = 0) -> tuple[float, float]:
        """Ball centre in the cup frame (m): (distance from the cone axis, height above throat)."""
        offset = self.ball_position(ball) - self.data.site_xpos[self._cup_site]
        local = self.data.site_xmat[self._cup_site].reshape(3, 3).T @ offset
        return math.hypot(local[0], local[1]), float(local[2])

    def ball_in_cup(self, ball: int = 0) -> bool:
        """Whether ball ``ball``'s centre sat inside the cone, below its rim, after the step."""
        return self._in_cup[ball]

    def _measure_balls(self) -> None:
        """Set, per ball, ``_heights``, ``_in_cup`` (centre inside the cone, below the rim) and
        ``_clear_of_cup``: what a step's events, episode end and info read.

        Clear means more than a ball radius outside the cone: a ball sloshing up to the rim is
        neither caught again nor counted as lost.
        """
        self._heights, self._in_cup, self._clear_of_cup = [], [], []
        margin = self.ball_radius
        for ball in range(self.balls):
            self._heights.append(self._ball_height(ball))
            radial, height = self.ball_in_cup_frame(ball)
            self._in_cup.append(0.0 <= height <= scene.CUP_DEPTH and radial <= scene.CUP_TOP_RADIUS)
            self._clear_of_cup.append(
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

    def ball_position(self, ball: int = 0) -> np.ndarray:
        """The ball's centre (m, world frame)."""
        return self.data.qpos[self._balls_qpos[ball] : self._balls_qpos[ball] + 3]

    def ball_velocity(self, ball: int = 0) -> np.ndarray:
        """The ball's linear velocity (m/s, world frame)."""
        return self.data.qvel[self._balls_qvel[ball] : self._balls_qvel[ball] + 3]

    def cup_position(self) -> np.ndarray:
        """The cup's throat (site ``cup``, m, world frame), from the last physics step."""
        return self.data.site_xpos[self._cup_site]
