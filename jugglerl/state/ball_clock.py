"""``BallClock``: the time since the ball last fell into the cup's reach, as a transform.

The episode clock (``TimestampFeatures``) knows where a cycle of fixed length is, but a closed
loop does not keep a fixed cycle: the teacher (``FeedbackPolicy``) re-times its command each
time the falling ball passes ``LOCK_HEIGHT`` above the cup, so after a few throws its phase and
the episode clock have drifted apart, and a network that sees only the episode clock cannot
tell where the teacher is in its command (offline, an MLP imitating a teacher that resets its
phase at each lock erred on the elbow by RMS 0.057 in normalised action units with the episode
clock, 0.018 with this one, 0.014 given the teacher's phase itself; docs/results/apprentice.md).
This transform measures that event from the observation, as the teacher does, and appends
``phase_features`` of the time since it (``2 harmonics`` values) to ``state``:

- the moment the falling ball (``vz < 0``) passes ``height`` above the cup is interpolated
  within the step from the relative vertical speed; the ball must rise ``rearm`` above
  ``height`` before the next one counts;
- before the first such moment the clock counts from the episode's start.

It is sensing, not control: the clock is a function of the observed ball and cup. Its memory
(the last lock time and whether it is armed) travels in the tensordict as ``ball_clock_lock``
and ``ball_clock_armed`` (``carried_keys``), so batched envs reset per env; a deployed actor's
encoder (``jugglerl.state.encoder``) runs the same ``clock_step`` on plain tensors.
"""

from __future__ import annotations

import torch
from tensordict import TensorDictBase
from torchrl.data import Binary, Unbounded
from torchrl.envs import Transform

from jugglerl.state.spec import resized
from jugglerl.state.timestamp import phase_features

#: Observation indices (``jugglerl_envs.measurements``): ball z and vz, cup z and vz.
BALL_Z, BALL_VZ, CUP_Z, CUP_VZ = 8, 11, 14, 17
LOCK = "ball_clock_lock"
ARMED = "ball_clock_armed"


def num_ball_clock_features(harmonics: int) -> int:
    return 2 * harmonics


def clock_step(
    observation: torch.Tensor,
    time: torch.Tensor,
    fresh: torch.Tensor,
    lock: torch.Tensor,
    armed: torch.Tensor,
    height: float,
    rearm: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """The clock's memory after one observation: ``(lock, armed)`` from the last step's (both of
    ``time``'s shape; ``fresh`` envs start over at ``time``)."""
    lock = torch.where(fresh, time, lock)
    armed = armed | fresh
    above = observation[..., BALL_Z] - observation[..., CUP_Z]
    closing = (observation[..., CUP_VZ] - observation[..., BALL_VZ]).clamp(min=1e-3)
    crossing = armed & (above < height) & (observation[..., BALL_VZ] < 0)
    lock = torch.where(crossing, time - (height - above) / closing, lock)
    armed = (armed & ~crossing) | (above > height + rearm)
    return lock, armed


class BallClock(Transform):
    """Appends ``phase_features`` of the ball clock (see the module docstring) to ``state``."""

    carried_keys = (LOCK, ARMED)

    def __init__(self, period: float, harmonics: int = 1, height: float = 0.2, rearm: float = 0.05):
        if period <= 0 or height <= 0 or rearm < 0:
            raise ValueError(
                f"ball clock: period={period} and height={height} must be > 0, rearm={rearm} >= 0"
            )
        super().__init__(in_keys=["observation", "time", "is_init"], out_keys=["state"])
        self.period, self.harmonics = float(period), int(harmonics)
        self.height, self.rearm = float(height), float(rearm)

    def _call(self, tensordict: TensorDictBase) -> TensorDictBase:
        observation = tensordict.get("observation")
        batch = observation.shape[:-1]
        time = tensordict.get("time").reshape(batch).to(torch.float64)
        fresh = tensordict.get("is_init").reshape(batch)
        lock = tensordict.get(LOCK, None)
        armed = tensordict.get(ARMED, None)
        if lock is None:
            lock, armed = time.clone(), torch.ones(batch, dtype=torch.bool)
        lock, armed = clock_step(
            observation,
            time,
            fresh,
            lock.reshape(batch),
            armed.reshape(batch),
            self.height,
            self.rearm,
        )
        state = tensordict.get("state")
        features = phase_features(time - lock, self.period, self.harmonics).to(state.dtype)
        tensordict.set(LOCK, lock)
        tensordict.set(ARMED, armed)
        return tensordict.set("state", torch.cat([state, features], dim=-1))

    forward = _call

    def _carry(self, source: TensorDictBase | None, target: TensorDictBase) -> TensorDictBase:
        """``target`` with the memory ``source`` holds (none on a first reset)."""
        for key in self.carried_keys:
            if source is not None and key in source:
                target.set(key, source.get(key))
        return target

    def _step(self, tensordict: TensorDictBase, next_tensordict: TensorDictBase):
        return self._call(self._carry(tensordict, next_tensordict))  # this step's, for the next

    def _reset(self, tensordict: TensorDictBase, tensordict_reset: TensorDictBase):
        # envs that do not reset keep their memory; those that do restart it (``is_init``)
        return self._call(self._carry(tensordict, tensordict_reset))

    def transform_observation_spec(self, observation_spec):
        spec = observation_spec["state"]
        features = num_ball_clock_features(self.harmonics)
        batch = spec.shape[:-1]
        observation_spec["state"] = resized(spec, spec.shape[-1] + features)
        observation_spec[LOCK] = Unbounded(shape=batch, dtype=torch.float64, device=spec.device)
        observation_spec[ARMED] = Binary(shape=batch, dtype=torch.bool, device=spec.device)
        return observation_spec
