"""``ObservationParts``: which parts of the env's observation the networks see (``state.observe``).

The env observes 18 values (``envs/juggle.py``): the three actuated joints' angles and velocities,
the ball's position and velocity and the cup's throat position and velocity, all in the world
frame. ``state.observe`` lists the parts that make up the networks' ``state``, in order:

| part | values |
| --- | --- |
| ``joints``, ``joint_velocities`` | pan, lift, elbow (rad, rad/s) |
| ``ball``, ``ball_velocity`` | the ball (m, m/s) |
| ``cup``, ``cup_velocity`` | the cup's throat (m, m/s) |
| ``ball_from_cup`` | the ball's position relative to the throat (m) |

All six observed parts is the default. The teacher (``FeedbackPolicy``) reads only the ball
relative to the cup and the two velocities; a student given just that
(``[ball_from_cup, ball_velocity, cup_velocity]`` and the clocks) cannot lean on where the arm
is, but measured in ``algo=apprentice`` it did not hold the juggling cycle either
(docs/results/apprentice.md), so the arm's state stays in by default.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
from tensordict import TensorDictBase
from torchrl.envs import Transform

from jugglerl.state.spec import resized

#: The observed parts: slices of the env's observation.
OBSERVED = {
    "joints": slice(0, 3),
    "joint_velocities": slice(3, 6),
    "ball": slice(6, 9),
    "ball_velocity": slice(9, 12),
    "cup": slice(12, 15),
    "cup_velocity": slice(15, 18),
}
#: The values the parts are cut from: the one-ball observation.
OBSERVED_SIZE = max(part.stop for part in OBSERVED.values())
#: The whole observation in its order: the default, and a selection that needs no cutting.
WHOLE_OBSERVATION = tuple(OBSERVED)
#: Every part there is, each of three values.
PARTS = (*OBSERVED, "ball_from_cup")
PART_SIZE = 3


def observed_parts(state_cfg) -> tuple[str, ...]:
    """``state.observe``, checked: every name a part, none twice, at least one; runs saved
    before the key existed saw the whole observation."""
    parts = state_cfg.get("observe")
    parts = WHOLE_OBSERVATION if parts is None else tuple(parts)
    unknown = [part for part in parts if part not in PARTS]
    if not parts or unknown or len(set(parts)) != len(parts):
        raise ValueError(
            f"state.observe={list(parts)}: one or more of {', '.join(PARTS)}, each at most once"
            + (f" (not {', '.join(unknown)})" if unknown else "")
        )
    return parts


def part_values(observation: torch.Tensor, part: str) -> torch.Tensor:
    """The three values of ``part`` of ``observation`` (last dim the env's 18)."""
    if part == "ball_from_cup":
        return observation[..., OBSERVED["ball"]] - observation[..., OBSERVED["cup"]]
    return observation[..., OBSERVED[part]]


class ObservationParts(Transform):
    """Replaces ``key`` (the env's observation, or a float copy of it) by its ``parts``."""

    def __init__(self, parts: Sequence[str], key: str = "state"):
        super().__init__(in_keys=[key], out_keys=[key])
        self.parts = tuple(parts)
        self.key = key

    def _call(self, tensordict: TensorDictBase) -> TensorDictBase:
        observation = tensordict.get(self.key)
        values = [part_values(observation, part) for part in self.parts]
        return tensordict.set(self.key, torch.cat(values, dim=-1))

    forward = _call

    def _reset(self, tensordict: TensorDictBase, tensordict_reset: TensorDictBase):
        return self._call(tensordict_reset)

    def transform_observation_spec(self, observation_spec):
        spec = observation_spec[self.key]
        observation_spec[self.key] = resized(spec, PART_SIZE * len(self.parts))
        return observation_spec
