"""A command-line override of the wrong type, a group choice without its file and a key the config
does not have end the scripts with one line naming what to change."""

import pytest
from cli import run_script
from omegaconf import OmegaConf

from jugglerl.config.command_line import (
    CONFIG_DIR,
    type_mismatch,
    unknown_group_choice,
    unknown_key,
)


@pytest.mark.parametrize(
    ("script", "override", "message"),
    [
        ("train.py", "optim.lr_actor=abc", "error: optim.lr_actor=abc: expected a number (float)"),
        # a group choice on the same line selects the default compared with: actor/lstm.yaml's
        (
            "train.py",
            "actor=lstm actor.hidden_size=1e2",
            "error: actor.hidden_size=1e2: expected an integer (int)",
        ),
        ("evaluate.py", "seed=1.5", "error: seed=1.5: expected an integer (int)"),
        ("robustness.py", "seeds=x", "error: seeds=x: expected an integer (int)"),
    ],
)
def test_a_mistyped_override_is_one_error_line(tmp_path, script, override, message):
    result = run_script(script, *override.split(), f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].endswith(message)
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("default", "value", "expected"),
    [
        (1.0e-4, "abc", "a number (float)"),
        (1.0e-4, 3, None),  # an int is a number
        (1.0e-4, True, "a number (float)"),
        (61440, 1.5, "an integer (int)"),
        (61440, 2048, None),
        (True, "yes", "true or false (bool)"),
        (False, True, None),
        ("expert", 3, None),  # policy=3 is a name too
        ("expert", [1], "a string"),
        (None, "anything", None),  # a null default takes any value
        (OmegaConf.create([256, 256]), 5, "a list, e.g. [a,b]"),
        (OmegaConf.create([256, 256]), [64], None),
        (OmegaConf.create({"a": 1}), 1, "a mapping, e.g. {key:value}"),
        (1.0, None, None),  # null switches a key off
    ],
)
def test_values_are_compared_with_the_type_of_the_default(default, value, expected):
    assert type_mismatch(default, value) == expected


@pytest.mark.parametrize(
    ("script", "override", "message"),
    [
        ("train.py", "actor=gru", "error: actor=gru is not available; choose one of lstm, mlp,"),
        ("train.py", "-m actor=mlp,gru", "error: actor=gru is not available; choose one of lstm"),
        ("train.py", "+experiment=nope", "error: experiment=nope is not available; choose one"),
        ("evaluate.py", "env=mars", "error: env=mars is not available; choose one of earth, paper"),
        ("robustness.py", "cluster=slurm", "error: cluster=slurm is not available; choose one of"),
        ("export_policy.py", "logger=x", "error: logger=x is not available; choose one of"),
        (
            "train.py",
            "optim.lr_actorr=1",
            "error: optim.lr_actorr=1: the config has no optim.lr_actorr; optim has lr_actor,",
        ),
        ("evaluate.py", "durationn=2", "error: durationn=2: the config has no durationn; the"),
    ],
)
def test_an_unknown_group_choice_or_key_is_one_error_line(tmp_path, script, override, message):
    result = run_script(script, *override.split(), f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1
    assert result.stderr.strip() == result.stderr.strip().splitlines()[0]
    assert result.stderr.startswith(message), result.stderr


def test_group_choices_that_exist_or_are_not_groups_pass(tmp_path):
    for group in ("actor", "algo"):
        (tmp_path / group).mkdir()
        (tmp_path / group / "mlp.yaml").write_text("{}")
    lines = ["actor=mlp", "-m", "algo=mlp", "actor.hidden=[1]", "seed=3", "~actor", "hydra.x=1"]
    assert unknown_group_choice(lines, tmp_path) is None
    assert "actor=lstm" in unknown_group_choice(["actor=mlp,lstm"], tmp_path)


def test_keys_are_looked_up_in_the_config_the_group_choices_compose():
    def problem(*arguments):
        return unknown_key(arguments, "train", CONFIG_DIR)

    assert problem("algo=dps", "algo.episodes=4", "-m", "seed=0,1", "+eval.perturbed.x={}") is None
    assert problem("hydra.run.dir=x", "~init_actor", "algo.stages.bc.until=4") is None
    assert problem("algo.episodes=4").startswith(
        "algo.episodes=4: the config has no algo.episodes; algo has bc_tau,"
    )  # the default algo (apprentice) has none
    assert problem("algo.stages.rl.until=4") == (
        "algo.stages.rl.until=4: the config has no algo.stages.rl.until; algo.stages has bc, dagger"
    )
    assert "the config has no foo.x; the config has actor, algo," in problem("foo.x=1")
    assert "repeat the run's group choices, e.g. algo=dps" in problem("resume=R", "algo.episodes=4")
