"""Neural policies shipped by name (``kind: actor`` files): the shipped ``lstm_juggler`` juggles
on its own, and ``scripts/ship_actor.py`` writes a file that deploys what its run deploys."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from cli import train_config
from omegaconf import OmegaConf

import jugglerl.policies.feedback as feedback
import jugglerl.policies.throw_catch as throw_catch
from jugglerl.config.envs import make_juggle_env
from jugglerl.networks.actors import ACTION_SIZE, build_actor
from jugglerl.policies.actor import ActorPolicy
from jugglerl.policies.actor_file import write_actor_policy
from jugglerl.policies.episodes import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl.runs.policy_files import PolicyFileError
from jugglerl.state.transforms import state_size
from jugglerl_envs import JuggleEnv


@pytest.mark.slow
def test_lstm_juggler_juggles_by_name_with_no_feedback_policy_built(monkeypatch):
    built = []
    real_init = feedback.FeedbackPolicy.__init__

    def counting_init(self, *args, **kwargs):
        built.append(self)
        real_init(self, *args, **kwargs)

    monkeypatch.setattr(feedback.FeedbackPolicy, "__init__", counting_init)
    env = make_juggle_env(train_config().env, duration=120.0)
    policy = load_policy("lstm_juggler", env)
    assert isinstance(policy, ActorPolicy)
    episode = run_episode(env, policy, seed=0)
    env.close()
    assert not built, "a FeedbackPolicy was built: the shipped network must act alone"
    assert episode.throws >= 39 and episode.max_cup_height <= 0.76


@pytest.mark.slow
def test_earth_lstm_juggles_at_real_gravity_as_a_network_alone(monkeypatch):
    built = []
    for kind in (feedback.FeedbackPolicy, throw_catch.ThrowCatchPolicy):
        monkeypatch.setattr(kind, "__init__", lambda self, *args, **kwargs: built.append(self))
    earth = make_juggle_env(train_config("env=earth").env, duration=10.0)
    policy = load_policy("earth_lstm", earth)
    assert isinstance(policy, ActorPolicy)
    episode = run_episode(earth, policy, seed=0)
    earth.close()
    assert not built, "a hand-written controller was built: the shipped network must act alone"
    assert episode.throws >= 3 and episode.time_to_drop is None  # a throw every 1.8 s after 2 s
    assert max(episode.peak_joint_speed) <= math.pi and episode.max_cup_height <= 0.76
    with pytest.raises(PolicyFileError, match=r"learnt at env.gravity=-9.81 \(env=earth\)"):
        load_policy("earth_lstm", JuggleEnv())  # the paper's gravity


def test_a_shipped_actor_file_acts_as_the_run_it_came_from(tmp_path):
    cfg = train_config("algo=bc", "actor=lstm", "state.ball_clock=true")
    torch.manual_seed(0)
    actor = build_actor(cfg.actor, state_size(cfg.state), ACTION_SIZE)
    state = {
        "config": OmegaConf.to_container(cfg, resolve=True),
        "policy": actor.state_dict(),
        "normalisation": {"loc": torch.rand(18), "scale": 1 + torch.rand(18)},
    }
    path = write_actor_policy(state, tmp_path, "student", "trained here\n\nfor a test")
    assert path.read_text().startswith("# trained here\n#\n# for a test\nkind: actor\n")
    env = make_juggle_env(train_config().env, duration=2.0)
    shipped, original = load_policy(str(path), env), ActorPolicy.from_state(state)
    observation, info = env.reset(seed=0)
    for _ in range(20):  # the recurrent and ball-clock memories carried alike
        action = shipped.act(observation, info["time"])
        np.testing.assert_array_equal(action, original.act(observation, info["time"]))
        observation, *_, info = env.step(action)
    env.close()


def test_an_actor_file_without_its_weights_is_a_one_line_error(tmp_path):
    (tmp_path / "lost.yaml").write_text("kind: actor\nweights: lost.pt\n")
    with make_juggle_env(train_config().env) as env, pytest.raises(ValueError, match="no weights"):
        load_policy(str(tmp_path / "lost.yaml"), env)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"PK\x03\x04 cut short", "not a readable weights file"),
        (None, "not an actor's weights (no config, normalisation)"),
    ],
)
def test_an_actor_file_with_broken_or_foreign_weights_is_a_one_line_error(
    tmp_path, content, message
):
    weights = tmp_path / "odd.pt"
    if content is None:
        torch.save({"policy": {}}, weights)  # another program's file
    else:
        weights.write_bytes(content)
    (tmp_path / "odd.yaml").write_text("kind: actor\nweights: odd.pt\n")
    with make_juggle_env(train_config().env) as env, pytest.raises(ValueError) as raised:
        load_policy(str(tmp_path / "odd.yaml"), env)
    assert str(raised.value).startswith(f"{weights}: {message}")  # the torch error follows
    assert "\n" not in str(raised.value)
