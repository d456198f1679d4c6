"""``init_actor``: start a run's actor from a trained one (a shipped name, an actor file or a run).

The actor takes the trained one's deployed weights and the env stack its observation
normalisation, so a fine-tuning run (an RL stage on a shipped clone) sees exactly the inputs the
weights were trained on. Its ``state`` config and its actor (name and sizes, the correction
aside) must match; a correction on top (``actor.correction``) keeps its zero start.
"""

from __future__ import annotations

from omegaconf import DictConfig, OmegaConf
from torch import nn

from jugglerl.networks.actors.correction import Correction
from jugglerl.policies.actor_file import read_actor_weights
from jugglerl.runs.policy_files import PolicyFileError


def _plain(node) -> dict:
    return OmegaConf.to_container(node, resolve=True) if isinstance(node, DictConfig) else node


def initial_weights(cfg: DictConfig) -> dict:
    """The ``config``, ``policy`` weights and ``normalisation`` ``cfg.init_actor`` names;
    ``ValueError`` if they cannot start ``cfg``'s actor."""
    spec = str(cfg.init_actor)
    try:
        weights = read_actor_weights(spec)
    except PolicyFileError as error:
        raise ValueError(f"init_actor={spec}: {error}") from None
    saved = weights["config"]
    ours = {key: value for key, value in _plain(cfg.actor).items() if key != "correction"}
    theirs = {key: value for key, value in saved["actor"].items() if key != "correction"}
    if ours != theirs:
        raise ValueError(f"init_actor={spec}: its actor {theirs} is not this run's {ours}")
    state, theirs = _plain(cfg.state), saved["state"]
    differing = sorted(
        key
        for key in (state.keys() | theirs.keys()) - {"norm_frames"}  # its normalisation comes along
        if state.get(key) != theirs.get(key)
    )
    if differing:
        raise ValueError(f"init_actor={spec}: its state differs in {', '.join(differing)}")
    return weights


def load_base_weights(actor: nn.Module, weights: dict, spec: str) -> None:
    """Load ``weights`` into ``actor``, leaving only a correction's parameters as they are."""
    missing, unexpected = actor.load_state_dict(weights, strict=False)
    own = {
        f"{name}.{key}"
        for name, module in actor.named_modules()
        if isinstance(module, Correction)
        for key in module.state_dict()
    }
    if unexpected or set(missing) - own:
        raise ValueError(
            f"init_actor={spec}: its weights do not fit this actor"
            f" (missing {sorted(set(missing) - own)[:3]}, unexpected {sorted(unexpected)[:3]})"
        )
