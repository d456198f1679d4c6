"""Policy files: YAML mappings with a ``kind`` (``command``, the default, ``feedback``,
``throw_catch`` or ``actor``: a network whose weights lie beside it), and the shipped ones.

Every shipped policy is one file in ``assets/policies/`` (installed as package data of
``jugglerl_envs.assets``), named by its stem: ``policy=expert`` is ``assets/policies/expert.yaml``.
The shelves beside them (``SHELVES``) hold the policies that are not results but stay loadable
by name: the hand-made starts of searches (``starts/``) and the results later searches replaced
(``superseded/``).
"""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import yaml

from jugglerl.runs.files import write_atomically

SHIPPED_PACKAGE = "jugglerl_envs.assets"
SHIPPED_FOLDER = "policies"
SHELVES = ("starts", "superseded")
SUFFIXES = (".yaml", ".yml", ".json")


class PolicyFileError(ValueError):
    """A policy file that cannot be used; the message says what and where."""


def check_balls(data: dict, balls: int) -> None:
    """Refuse a policy file stating ``balls`` (the number it juggles) other than the env's."""
    if "balls" in data and data["balls"] != balls:
        raise PolicyFileError(
            f"policy {data['name']} juggles balls={data['balls']} but the env has {balls}: run"
            f" it with env.balls={data['balls']}"
        )


def shipped_folder() -> Path:
    return Path(str(resources.files(SHIPPED_PACKAGE).joinpath(SHIPPED_FOLDER)))


def shipped_names() -> list[str]:
    """Names of the shipped policies (``expert``, ``dps_best``, ``closed_loop``, ...)."""
    return sorted(path.stem for path in shipped_folder().glob("*.yaml"))


def shelved_names() -> list[str]:
    """Names of the policies on the shelves (``SHELVES``), loadable by name like the shipped."""
    folder = shipped_folder()
    return sorted(path.stem for shelf in SHELVES for path in (folder / shelf).glob("*.yaml"))


def named_file(name: str) -> Path:
    """Where a policy name's file would be: among the shipped ones, else on a shelf that has
    it."""
    folder = shipped_folder()
    for candidate in [folder, *(folder / shelf for shelf in SHELVES)]:
        if (candidate / f"{name}.yaml").is_file():
            return candidate / f"{name}.yaml"
    return folder / f"{name}.yaml"


def known_names() -> str:
    """The shipped names and the shelved ones, for error messages."""
    return f"{', '.join(shipped_names())} (shelved: {', '.join(shelved_names())})"


def policy_file(name_or_path: str | Path) -> Path:
    """The file a shipped name or a path names; ``PolicyFileError`` listing the shipped names if
    there is none."""
    path = Path(name_or_path)
    if path.suffix.lower() not in SUFFIXES:
        if len(path.parts) > 1 or path.exists():  # a path, not a shipped name
            raise PolicyFileError(
                f"{path}: not a run directory, a checkpoint (.pt) or a policy file"
                f" ({', '.join(SUFFIXES)}); shipped policies: {known_names()}"
            )
        path = named_file(str(name_or_path))
    if not path.is_file():
        raise PolicyFileError(f"no policy file at {path}; shipped policies: {known_names()}")
    return path


def check_policy_named(key: str, spec: str | Path) -> None:
    """``PolicyFileError`` starting ``key=spec:`` when the config key ``key`` names no policy:
    an empty value, or a name or path with no file behind it (a run directory is checked when
    its checkpoint is loaded, a file's content when it is read: those errors name the file)."""
    if spec is None or not str(spec).strip():
        raise PolicyFileError(
            f"{key} is empty: give a shipped policy ({known_names()}), a policy file"
            " or a run directory"
        )
    if not names_a_run(spec):
        try:
            policy_file(spec)
        except PolicyFileError as error:
            raise PolicyFileError(f"{key}={spec}: {error}") from None


def names_a_run(spec: str | Path) -> bool:
    """Whether a ``policy=``/``init_actor=`` argument names a training run (its directory or a
    ``.pt`` checkpoint) rather than a policy name or file."""
    path = Path(spec)
    return path.suffix == ".pt" or path.is_dir()


def read_policy_file(name_or_path: str | Path) -> tuple[dict, str]:
    """The mapping in a policy file (YAML or JSON) and its path as a string, for messages."""
    path = policy_file(name_or_path)
    try:
        text = path.read_text()
        data = json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError) as error:
        raise PolicyFileError(f"{path}: not valid {path.suffix[1:].upper()}: {error}") from None
    if not isinstance(data, dict):
        raise PolicyFileError(f"{path}: expected a mapping with a 'kind' key")
    return data, str(path)


def write_policy_file(data: dict, path: str | Path) -> Path:
    """Write a policy mapping as YAML (JSON for a ``.json`` path), keys in the given order,
    atomically (``jugglerl.runs.files``: a run's best policy so far is never half written)."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        text = json.dumps(data, indent=2)
    else:
        text = yaml.safe_dump(data, sort_keys=False)
    write_atomically(path, lambda file: file.write(text.encode()))
    return path
