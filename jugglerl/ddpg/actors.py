"""The networks: a deterministic actor (``mlp`` or ``lstm``) and an MLP critic.

Both actors read ``observation`` and write ``action`` in [-1, 1] (a tanh squashes their output
onto the action spec). The LSTM actor carries its hidden state in the tensordict
(``recurrent_state_h``/``_c``): the env stack needs its primer (``lstm_primer``), and updates run
it on sampled sub-trajectories under ``set_recurrent_mode(True)``.
"""

from __future__ import annotations

from omegaconf import DictConfig
from tensordict.nn import TensorDictModule, TensorDictSequential
from torchrl.data import TensorSpec
from torchrl.envs import Transform
from torchrl.modules import MLP, LSTMModule, TanhModule, ValueOperator

ACTORS = ("mlp", "lstm")


def make_actor(actor_cfg: DictConfig, observation_size: int, action_spec: TensorSpec):
    """The actor named by ``actor_cfg.name`` (``mlp``: ``hidden`` sizes; ``lstm``: an LSTM of
    ``hidden_size`` units followed by an MLP head of ``head`` sizes)."""
    if actor_cfg.name not in ACTORS:
        raise ValueError(
            f"actor={actor_cfg.name} is not available; choose one of {', '.join(ACTORS)}"
        )
    action_size = action_spec.shape[-1]
    bounds = action_spec.space  # of a batched env: one row per env, all alike
    squash = TanhModule(
        in_keys=["param"],
        out_keys=["action"],
        low=bounds.low.reshape(-1, action_size)[0],
        high=bounds.high.reshape(-1, action_size)[0],
    )
    if actor_cfg.name == "mlp":
        body = TensorDictModule(
            MLP(observation_size, action_size, num_cells=list(actor_cfg.hidden)),
            in_keys=["observation"],
            out_keys=["param"],
        )
        return TensorDictSequential(body, squash)
    lstm = LSTMModule(
        input_size=observation_size,
        hidden_size=actor_cfg.hidden_size,
        in_key="observation",
        out_key="memory",
    )
    head = TensorDictModule(
        MLP(actor_cfg.hidden_size, action_size, num_cells=list(actor_cfg.head)),
        in_keys=["memory"],
        out_keys=["param"],
    )
    return TensorDictSequential(lstm, head, squash)


def lstm_primer(actor: TensorDictSequential) -> Transform | None:
    """The env transform that adds the LSTM's zero states on reset (``None`` for an MLP)."""
    lstm = next((m for m in actor.module if isinstance(m, LSTMModule)), None)
    return None if lstm is None else lstm.make_tensordict_primer()


def is_recurrent(actor: TensorDictSequential) -> bool:
    return lstm_primer(actor) is not None


def make_critic(critic_cfg: DictConfig, observation_size: int, action_size: int) -> ValueOperator:
    """Q(observation, action): an MLP of ``critic_cfg.hidden`` sizes on both, concatenated."""
    return ValueOperator(
        MLP(observation_size + action_size, 1, num_cells=list(critic_cfg.hidden)),
        in_keys=["observation", "action"],
    )
