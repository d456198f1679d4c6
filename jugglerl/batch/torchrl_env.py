"""``JuggleBatchEnv``: a ``JuggleBatch`` as one TorchRL env of ``batch_size=[N]``.

Keys (every entry one row per env):

| key | spec | what |
| --- | --- | --- |
| ``observation`` | float64 ``[N, obs]`` | the env's observation (``jugglerl_envs.juggle``) |
| ``time`` | float64 ``[N]`` | s since the env's episode started (the time features read it) |
| ``throws``, ``catches`` | int64 ``[N]`` | the episode's counts so far |
| ``physics_error`` | bool ``[N]`` | the physics went bad (the episode is terminated) |
| ``action`` | float32 ``[N, act]`` in [-1, 1] | normalised servo setpoints |
| ``reward`` | float32 ``[N, 1]`` | the env's ``reward`` |
| ``terminated``, ``truncated``, ``done`` | bool ``[N, 1]`` | a drop (bad physics); the time limit |

A drop is ``terminated``, the end of ``duration`` only ``truncated``, so value targets bootstrap
through the time limit. ``_reset`` honours the ``_reset`` mask: the envs it names start new
episodes, the others go on. ``set_seed(S)`` seeds env ``i`` with ``S + i`` for its next episode,
as Gymnasium's vector envs do. The batch itself (``env.batch``) saves and loads its whole state.
"""

from __future__ import annotations

import numpy as np
import torch
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from jugglerl_envs import JuggleBatch

#: The info entries the env carries, and their dtypes.
INFO_KEYS = {"throws": torch.int64, "catches": torch.int64, "time": torch.float64}


class JuggleBatchEnv(EnvBase):
    """``num_envs`` juggling envs of ``JuggleBatch``'s ``arguments`` (any may be one value per
    env), stepped by ``threads`` threads."""

    def __init__(self, num_envs: int, threads: int | None = None, **arguments):
        self.batch = JuggleBatch(num_envs, threads=threads, autoreset=False, **arguments)
        super().__init__(batch_size=torch.Size([num_envs]))
        n = num_envs
        size = self.batch.single_observation_space.shape[0]
        self.observation_spec = Composite(
            observation=Unbounded((n, size), dtype=torch.float64),
            physics_error=Unbounded((n,), dtype=torch.bool),
            **{key: Unbounded((n,), dtype=dtype) for key, dtype in INFO_KEYS.items()},
            shape=(n,),
        )
        self.action_spec = Bounded(-1.0, 1.0, (n, self.batch.servos), dtype=torch.float32)
        self.reward_spec = Unbounded((n, 1), dtype=torch.float32)
        self.done_spec = Composite(
            {key: Categorical(2, (n, 1), dtype=torch.bool) for key in DONE_KEYS}, shape=(n,)
        )

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs) -> TensorDictBase:
        mask = None
        if tensordict is not None and "_reset" in tensordict:
            mask = tensordict.get("_reset").reshape(-1).numpy()
        observations, info = self.batch.reset(options={"reset_mask": mask})
        not_done = np.zeros(self.batch.num_envs, dtype=bool)
        return self._output(observations, info, not_done, not_done)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        actions = tensordict.get("action").detach().numpy()
        observations, rewards, terminated, truncated, info = self.batch.step(actions)
        out = self._output(observations, info, terminated, truncated)
        out.set("reward", torch.as_tensor(rewards, dtype=torch.float32).unsqueeze(-1))
        return out

    def _output(self, observations, info, terminated, truncated) -> TensorDict:
        ends = {
            "terminated": torch.as_tensor(terminated).unsqueeze(-1),
            "truncated": torch.as_tensor(truncated).unsqueeze(-1),
        }
        ends["done"] = ends["terminated"] | ends["truncated"]
        values = {
            "observation": torch.as_tensor(observations),
            "physics_error": torch.as_tensor(info["physics_error"] != ""),
            **{key: torch.as_tensor(info[key], dtype=d) for key, d in INFO_KEYS.items()},
            **ends,
        }
        return TensorDict(values, batch_size=self.batch_size)

    def _set_seed(self, seed: int | None) -> None:
        self.batch.seed(seed)

    def close(self, *, raise_if_closed: bool = True) -> None:
        self.batch.close()
        super().close(raise_if_closed=raise_if_closed)


DONE_KEYS = ("done", "terminated", "truncated")
