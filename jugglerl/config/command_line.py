"""Command-line overrides checked against the types of the defaults they replace, and group
choices and keys against the configs.

Hydra takes ``optim.lr_actor=abc`` as the string ``"abc"`` (the configs have no schema), and the
mistake surfaces much later as a traceback deep in the training code. ``check_override_types``,
called first thing in a script's ``main``, turns it into one line naming the key and the type
its default has: ``optim.lr_actor=abc: expected a number (float)``. A choice of a config group
that has no file (``actor=gru``) and a key the config does not have (``optim.lr=1``) fail before
``main``, in Hydra's composition, with 6-15 lines; ``exit_on_bad_command_line``, called before
Hydra starts, says each in one, as the registries do: ``error: actor=gru is not available;
choose one of lstm, mlp, residual``, ``error: optim.lr=1: the config has no optim.lr; optim has
lr_actor, lr_critic, …``.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from omegaconf import DictConfig, ListConfig, OmegaConf

_ABSENT = object()
#: ``configs/``, installed as package data of ``jugglerl.configs``: where the scripts' Hydra
#: configs and their groups are.
CONFIG_DIR = Path(str(resources.files("jugglerl.configs")))
#: Mappings whose entries are the user's to name (conditions, stages), checked where they are
#: read; a ``+key`` anywhere else adds what nothing reads.
OPEN_MAPPINGS = (
    "eval.perturbed",
    "algo.teacher_perturbed",
    "algo.student_perturbed",
    "algo.stages",
    "families",
    "hydra",
)


def check_override_types(overrides: Sequence[str] | None = None) -> None:
    """Raise ``ValueError`` for the first override whose value has another type than its default.

    ``overrides`` default to the running Hydra app's command line. The defaults are the app's
    config composed with the command line's group choices only (``actor=lstm``), so a key is
    compared with the default of the group actually chosen. Keys without a default (``+key=``),
    defaults that are ``null``, sweeps and deletions are not checked.
    """
    hydra = HydraConfig.get()
    if overrides is None:
        overrides = list(hydra.overrides.task)
    parsed = OverridesParser.create().parse_overrides(list(overrides))
    groups = set(hydra.runtime.choices)
    choices = [str(o.input_line) for o in parsed if o.key_or_group in groups]
    defaults = compose(hydra.job.config_name, overrides=choices)
    for override in parsed:
        if override.key_or_group in groups or override.is_delete() or override.is_sweep_override():
            continue
        if override.is_add():
            check_added_key(defaults, override.key_or_group, override.input_line)
            continue
        default = OmegaConf.select(defaults, override.key_or_group, default=_ABSENT)
        problem = type_mismatch(default, override.value())
        if problem:
            raise ValueError(f"{override.input_line}: expected {problem}")


def check_added_key(defaults: DictConfig, key: str, line: str) -> None:
    """``ValueError`` for a ``+key`` that adds what nothing reads: a key outside the mappings
    whose entries the user names (``OPEN_MAPPINGS``), naming the keys its parent has."""
    if any(key == mapping or key.startswith(mapping + ".") for mapping in OPEN_MAPPINGS):
        return
    parent_key, _, name = key.rpartition(".")
    parent = OmegaConf.select(defaults, parent_key) if parent_key else defaults
    if not isinstance(parent, DictConfig) or name in parent:
        return  # under a list or a value, or already there: the type check's or Hydra's
    where = parent_key or "the config"
    raise ValueError(f"{line}: nothing reads {key}; {where} has {', '.join(sorted(parent))}")


def type_mismatch(default, value) -> str | None:
    """What ``value`` should have been to replace ``default`` (e.g. ``"a number (float)"``),
    or ``None`` when it fits: an int fits a float, any scalar fits a string, anything fits a
    default that is absent or ``null``."""
    if default is _ABSENT or default is None or value is None:
        return None
    if isinstance(default, bool):
        return None if isinstance(value, bool) else "true or false (bool)"
    if isinstance(default, int):
        fits = isinstance(value, int) and not isinstance(value, bool)
        return None if fits else "an integer (int)"
    if isinstance(default, float):
        fits = isinstance(value, (int, float)) and not isinstance(value, bool)
        return None if fits else "a number (float)"
    if isinstance(default, str):
        return None if isinstance(value, (str, int, float, bool)) else "a string"
    if isinstance(default, ListConfig):
        return None if isinstance(value, list) else "a list, e.g. [a,b]"
    if isinstance(default, DictConfig):
        return None if isinstance(value, dict) else "a mapping, e.g. {key:value}"
    return None


def unknown_group_choice(arguments: Sequence[str], config_dir: Path) -> str | None:
    """What is wrong with the first ``group=choice`` of ``arguments`` (a command line) whose
    group is a folder of ``config_dir`` and has no ``choice.yaml`` (each choice of a sweep,
    ``actor=mlp,lstm``, counts), or ``None``. Hydra's own groups and sweep functions are left to
    Hydra."""
    for argument in arguments:
        key, equals, value = argument.partition("=")
        group = key.lstrip("+~")
        if not equals or argument.startswith("-") or group.startswith("hydra") or "(" in value:
            continue
        folder = config_dir / group
        if "." in group or not folder.is_dir():
            continue
        options = sorted(path.stem for path in folder.glob("*.yaml"))
        for choice in value.split(","):
            if choice not in options:
                return f"{group}={choice} is not available; choose one of {', '.join(options)}"
    return None


def unknown_key(arguments: Sequence[str], config_name: str, config_dir: Path) -> str | None:
    """What is wrong with the first plain ``key=value`` of ``arguments`` (a command line) whose
    key the config ``config_name`` does not have once the command line's group choices are
    composed (Hydra refuses those), naming the keys its nearest parent has; or ``None``. Adds
    (``+key``), deletions and Hydra's own keys are left to the other checks and to Hydra."""
    try:
        parsed = OverridesParser.create().parse_overrides(
            [a for a in arguments if not a.startswith("-")]
        )
    except Exception:  # a malformed line: Hydra's parser says what is wrong with it
        return None
    groups, plain = [], []
    for override in parsed:
        key = override.key_or_group
        if key.startswith("hydra") or override.is_delete() or override.is_force_add():
            continue
        if (config_dir / key).is_dir():  # a group choice; a sweep's first choice stands for all
            first = str(override.input_line).partition("=")[2].split(",")[0]
            groups.append(f"{'+' if override.is_add() else ''}{key}={first}")
        elif not override.is_add():
            plain.append(override)
    if not plain:
        return None
    with initialize_config_dir(str(config_dir), version_base="1.3"):
        try:
            defaults = compose(config_name, overrides=groups)
        except Exception:  # a group's own problem: Hydra reports it
            return None
    for override in plain:
        key = override.key_or_group
        if OmegaConf.select(defaults, key, default=_ABSENT) is not _ABSENT:
            continue
        parent_key = key
        parent = _ABSENT
        while parent_key and parent is _ABSENT:
            parent_key = parent_key.rpartition(".")[0]
            parent = (
                OmegaConf.select(defaults, parent_key, default=_ABSENT) if parent_key else defaults
            )
        line = override.input_line
        problem = f"{line}: the config has no {key}"
        if isinstance(parent, DictConfig):
            problem += f"; {parent_key or 'the config'} has {', '.join(sorted(parent))}"
        if any(argument.startswith("resume=") for argument in arguments):
            problem += " (a resume's overrides are checked against the config this command line"
            problem += " composes: repeat the run's group choices, e.g. algo=dps)"
        return problem
    return None


def exit_on_bad_command_line(config_name: str) -> None:
    """End the script with one ``error:`` line when its command line chooses a config group
    option that the project's configs (``CONFIG_DIR``) do not hold, or sets a key that its
    config ``config_name`` does not have."""
    problem = unknown_group_choice(sys.argv[1:], CONFIG_DIR) or unknown_key(
        sys.argv[1:], config_name, CONFIG_DIR
    )
    if problem:
        sys.exit(f"error: {problem}")
