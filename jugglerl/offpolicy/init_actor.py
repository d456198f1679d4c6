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
    """Load ``weights`` into ``actor``. A correction of ``actor`` keeps its own parameters where
    the weights have none; a correction the weights carry on top of a base like ``actor``'s
    (the next module of its sequence) is left out when it is at its zero start, where it acts as
    nothing, and refused when it has trained."""
    on_top = f"module.{len(actor.module)}.module."
    carried = {key: value for key, value in weights.items() if key.startswith(on_top)}
    if carried and not _at_zero(carried):
        raise ValueError(
            f"init_actor={spec}: it carries a trained correction (actor.correction), which this"
            " actor lacks: start from it with the same actor.correction"
        )
    missing, unexpected = actor.load_state_dict(weights, strict=False)
    unexpected = [key for key in unexpected if key not in carried]
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


def _at_zero(correction: dict) -> bool:
    """Whether a correction's weights (``...body.<layer>.weight``/``bias``) end in a zero layer."""
    last = max(int(key.split("body.")[1].split(".")[0]) for key in correction)
    return all(not value.any() for key, value in correction.items() if f"body.{last}." in key)
