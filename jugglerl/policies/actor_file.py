"""Actor policy files (``kind: actor``): a trained network shipped by name, without its run.

A policy file ``NAME.yaml`` with ``kind: actor`` names a weights file beside it (``weights:
NAME.pt``) that holds what ``ActorPolicy`` needs and nothing of the training: the actor and state
config, the deployed weights and the observation normalisation (a few hundred kB, where the run's
``checkpoint.pt`` also carries critics, optimisers and history). ``scripts/ship_actor.py`` writes
the pair from a run; ``policy=NAME`` then loads it like any shipped policy.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from jugglerl.runs.policy_files import PolicyFileError, names_a_run, read_policy_file

#: The parts of a run's config an actor policy needs (``ActorPolicy.from_config``).
CONFIG_KEYS = ("actor", "state", "env")
#: What a weights file holds (``write_actor_policy`` writes them).
WEIGHT_KEYS = ("config", "policy", "normalisation")


def _weights_from_dict(data: dict, source: str) -> dict:
    import torch  # only actor files need it

    if data.get("kind") != "actor" or "weights" not in data:
        raise PolicyFileError(f"{source}: not a kind: actor file with 'weights: FILE.pt'")
    path = Path(source).parent / data["weights"]
    if not path.is_file():
        raise PolicyFileError(f"{source}: no weights file at {path}")
    try:
        weights = torch.load(path, weights_only=False)
    except Exception as error:  # truncated, or not a torch file: pickle, zip and EOF errors
        raise PolicyFileError(f"{path}: not a readable weights file ({error})") from None
    missing = [key for key in WEIGHT_KEYS if not isinstance(weights, dict) or key not in weights]
    if missing:
        raise PolicyFileError(f"{path}: not an actor's weights (no {', '.join(missing)})")
    return weights


def check_gravity(config: dict, env, source: str, preset: str | None = None) -> None:
    """``PolicyFileError`` when ``env`` pulls otherwise than the env an actor learnt in (its
    ``preset``, when its policy file names one): a network does not carry over between
    gravities (an earth actor drops the ball at once at the paper's -2 m/s²)."""
    learnt, here = config["env"].get("gravity", -2.0), env.unwrapped.gravity
    if learnt != here:
        named = f" (env={preset})" if preset else ""
        raise PolicyFileError(
            f"{source}: the actor learnt at env.gravity={learnt}{named}; this env has {here}"
        )


def actor_policy_from_dict(data: dict, source: str, env):
    """The ``ActorPolicy`` of a ``kind: actor`` file read from ``source``, for ``env``."""
    from jugglerl.policies.actor import ActorPolicy

    weights = _weights_from_dict(data, source)
    check_gravity(weights["config"], env, source, data.get("env"))
    return ActorPolicy.from_state(weights)


def read_actor_weights(spec: str) -> dict:
    """``config``, deployed ``policy`` weights and ``normalisation`` of a shipped actor name, a
    ``kind: actor`` file or an off-policy run (its directory or ``checkpoint.pt``)."""
    if names_a_run(spec):
        from jugglerl.runs.checkpoints import load_checkpoint

        state = load_checkpoint(spec)
        if state["deploys"] != "actor":
            raise PolicyFileError(f"{spec}: the run deploys {state['deploys']}, not an actor")
        return state
    return _weights_from_dict(*read_policy_file(spec))


def write_actor_policy(
    state: dict, folder: Path, name: str, header: str, env: str | None = None
) -> Path:
    """``folder/name.yaml`` (``header`` as its comment) and ``folder/name.pt`` from a training
    checkpoint's ``state`` (its deployed actor); returns the YAML's path. ``env``: the env preset
    it runs in (``configs/env/``), when not the default ``paper``."""
    import torch

    config = {key: state["config"][key] for key in CONFIG_KEYS}
    weights = {"config": config, "policy": state["policy"], "normalisation": state["normalisation"]}
    folder.mkdir(parents=True, exist_ok=True)
    torch.save(weights, folder / f"{name}.pt")
    comment = "".join(f"# {line}\n".replace("# \n", "#\n") for line in header.splitlines())
    data = {"kind": "actor", "weights": f"{name}.pt", **({"env": env} if env else {})}
    body = yaml.safe_dump(data, sort_keys=False)
    path = folder / f"{name}.yaml"
    path.write_text(comment + body)
    return path
