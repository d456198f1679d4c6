"""``TeacherModule``: any ``Policy`` acting inside the TorchRL loop, one copy per env of the batch.

A teacher (the closed-loop ``FeedbackPolicy``, an open-loop command, a trained actor) is a plain
policy with per-episode state, stepped on numpy observations. The module runs one copy of it per env
of the batch on the env stack's raw ``observation`` and ``time`` (kept beside the networks'
``state``, see ``jugglerl.batch.env_stack``), resets a copy when its env starts an episode
(``is_init``), and writes the actions under ``("teacher", "action")``: into the replay buffer with
each transition (the labels of behaviour cloning), and for ``WhoActs`` when the teacher acts.
"""

from __future__ import annotations

import copy

import gymnasium as gym
import numpy as np
import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModuleBase

from jugglerl.policies import Policy

#: Where the teacher writes its action for each transition (the cloning loss reads it, and
#: ``jugglerl.offpolicy.who_acts.WhoActs`` when the teacher acts).
TEACHER_ACTION = ("teacher", "action")


class TeacherModule(TensorDictModuleBase):
    """``num_envs`` copies of ``policy`` labelling a batch ``[num_envs]`` step by step."""

    in_keys = ["observation", "time", "is_init"]
    out_keys = [TEACHER_ACTION]

    def __init__(self, policy: Policy, num_envs: int):
        super().__init__()
        self.policies = [copy.deepcopy(policy) for _ in range(num_envs)]

    def forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        observations = tensordict.get("observation").detach().cpu().double().numpy()
        times = tensordict.get("time").detach().cpu().double().numpy().reshape(-1)
        starts = tensordict.get("is_init").detach().cpu().numpy().reshape(-1)
        if len(observations) != len(self.policies):
            raise ValueError(
                f"the teacher has {len(self.policies)} copies for a batch of {len(observations)}"
            )
        actions = np.empty((len(self.policies), 3), dtype=np.float32)
        for index, policy in enumerate(self.policies):
            if starts[index]:
                policy.reset()
            actions[index] = policy.act(observations[index], float(times[index]))
        return tensordict.set(TEACHER_ACTION, torch.from_numpy(actions))

    def episode_state(self) -> list[Policy]:
        """Each copy as it stands mid-episode (a checkpoint pickles them)."""
        return copy.deepcopy(self.policies)

    def load_episode_state(self, policies: list[Policy]) -> None:
        """Continue the episodes of ``episode_state()``."""
        if len(policies) != len(self.policies):
            raise ValueError(
                f"a checkpoint's teacher has {len(policies)} copies for {len(self.policies)} envs"
            )
        self.policies = copy.deepcopy(policies)


def teacher_period(policy: Policy, env: gym.Env) -> float:
    """The teacher's cycle (s), for the networks' phase features (``state.period: teacher``).

    A policy that plays a cyclic command (``CommandPolicy``, ``FeedbackPolicy``) has its
    command's cycle; any other (a throw-and-catch controller, a trained actor) the median time
    between its throws over one episode of ``env`` from the standard start. ``ValueError`` if
    it throws fewer than twice there.
    """
    command = getattr(policy, "command", None)
    if command is not None:
        return float(command.cycle)
    observation, info = env.reset(seed=0)
    policy.reset()
    throw_times, throws = [], info["throws"]
    terminated = truncated = False
    while not (terminated or truncated):
        observation, _, terminated, truncated, info = env.step(
            policy.act(observation, info["time"])
        )
        if info["throws"] > throws:
            throws = info["throws"]
            throw_times.append(info["time"])
    if len(throw_times) < 2:
        raise ValueError(
            f"state.period=teacher: the teacher threw {len(throw_times)} times in an episode"
            " from the standard start, too few to time its cycle; give state.period in s"
        )
    return float(np.median(np.diff(throw_times)))
