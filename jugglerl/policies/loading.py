"""``load_policy``: a ``policy=NAME|FILE|RUN_DIR`` argument as a runnable policy."""

from __future__ import annotations

import sys
from pathlib import Path

import gymnasium as gym

from jugglerl.commands import command_from_dict
from jugglerl.policies import Policy
from jugglerl.policies.actor_file import actor_policy_from_dict, check_gravity
from jugglerl.policies.command import CommandPolicy
from jugglerl.policies.feedback import feedback_policy_from_dict
from jugglerl.policies.throw_catch import throw_catch_policy_from_dict
from jugglerl.runs.files import METRICS
from jugglerl.runs.policy_files import (
    PolicyFileError,
    check_policy_named,
    names_a_run,
    read_policy_file,
)

#: Policy file kinds and their readers (``data, source, env -> Policy``).
FILE_KINDS = {
    "command": lambda data, source, env: CommandPolicy(command_from_dict(data, source)),
    "feedback": feedback_policy_from_dict,
    "actor": actor_policy_from_dict,
    "throw_catch": throw_catch_policy_from_dict,
}


def load_policy(spec: str, env: gym.Env) -> Policy:
    """A policy for envs like ``env`` from a shipped name (``expert``, ``closed_loop``, ...), a
    policy file (``kind: command``, the default, ``kind: feedback``, ``kind: throw_catch`` or
    ``kind: actor``) or a training run (its directory or ``checkpoint.pt``: the actor it deploys,
    or the best policy file of a search).

    Raises ``ValueError`` with a one-line reason when ``spec`` is unusable.
    """
    if names_a_run(spec):
        return _run_policy(Path(spec), env)
    data, source = read_policy_file(spec)
    kind = data.get("kind", "command")
    if kind not in FILE_KINDS:
        raise PolicyFileError(
            f"{source}: kind={kind!r} is not a policy kind; use one of {', '.join(FILE_KINDS)}"
        )
    return FILE_KINDS[kind](data, source, env)


def load_named_policy(key: str, spec, env: gym.Env) -> Policy:
    """``load_policy`` for the config key ``key`` (``policy``, ``teacher.policy``, ...): a value
    that names no policy is an error that names the key."""
    check_policy_named(key, spec)
    return load_policy(str(spec), env)


def _run_policy(path: Path, env: gym.Env) -> Policy:
    """What a training checkpoint says it deploys (``checkpoint["deploys"]``)."""
    from jugglerl.runs.checkpoints import load_checkpoint  # torch loads only for checkpoints

    state = load_checkpoint(path)
    run_dir = path if path.is_dir() else path.parent
    if not (run_dir / METRICS).exists():
        print(
            f"warning: {run_dir} holds an unfinished run (no {METRICS}: killed, still running or"
            " resumed): its last checkpoint's policy",
            file=sys.stderr,
        )
    deploys = state["deploys"]
    if deploys == "actor":
        from jugglerl.policies.actor import ActorPolicy

        check_gravity(state["config"], env, str(path))
        return ActorPolicy.from_state(state)
    return load_policy(str(run_dir / deploys), env)
