"""The periodic evaluation's perturbed conditions (``eval.perturbed``) and the score that
``eval.keep_best`` ranks."""

import re

import numpy as np
import pytest
from cli import train_config

from jugglerl.batch.evaluations import Evaluations, score
from jugglerl.config.envs import make_juggle_env
from jugglerl.offpolicy.checks import check_config
from jugglerl.policies.episodes import run_episode, summarise_episodes
from jugglerl.policies.loading import load_policy
from jugglerl.recording.logger import RerunLogger


def test_perturbed_conditions_run_their_own_episodes_and_enter_the_score(tmp_path):
    cfg = train_config(
        "~eval.perturbed",  # in place of algo=apprentice's conditions
        "+eval.perturbed.shaky={action_noise:0.05}",
        "eval.seeds=1",
        "eval.catch_time=1",
        "eval.record=false",
        "eval.perturbed_seeds=2",
        "eval.perturbed_duration=6",
    )
    env = make_juggle_env(cfg.env, duration=12.0)
    expert = load_policy("expert", env)  # juggles; noise of 0.05 breaks its throws
    evaluations = Evaluations(cfg)
    with RerunLogger.from_config(cfg.logger, tmp_path) as logger:
        record = evaluations.evaluate(expert, 0, logger, 12.0)

    shaky_env = make_juggle_env(cfg.env, duration=6.0, action_noise=0.05)
    by_hand = [run_episode(shaky_env, expert, seed=seed) for seed in (1000, 1001)]
    shaky = record["perturbed"]["shaky"]
    assert shaky == {"duration": 6.0, **summarise_episodes(by_hand, 1.0)}
    assert record["mean_throws"] >= 4 and shaky["mean_throws"] < record["mean_throws"] / 2
    # the nominal catch rate first; the 6-s condition's throws and time up count double
    # against the 12-s nominal episode
    expected = [
        record["catch_rate"],
        (record["mean_throws"] + 2 * shaky["mean_throws"]) / 2,
        (record["mean_time_to_drop"] + 2 * shaky["mean_time_to_drop"]) / 2,
    ]
    assert score(record) == pytest.approx(expected)


def test_a_condition_with_its_own_duration_and_seeds_runs_that_many_episodes_that_long(tmp_path):
    cfg = train_config(
        "~eval.perturbed",
        "+eval.perturbed.short={action_noise:0.05}",
        "+eval.perturbed.long={action_noise:0.05,duration:9,seeds:2}",
        "eval.seeds=1",
        "eval.catch_time=1",
        "eval.record=false",
        "eval.perturbed_duration=3",
    )
    env = make_juggle_env(cfg.env, duration=12.0)
    expert = load_policy("expert", env)
    with RerunLogger.from_config(cfg.logger, tmp_path) as logger:
        record = Evaluations(cfg).evaluate(expert, 0, logger, 12.0)

    long_env = make_juggle_env(cfg.env, duration=9.0, action_noise=0.05)
    by_hand = [run_episode(long_env, expert, seed=seed) for seed in (1000, 1001)]
    assert record["perturbed"]["long"] == {"duration": 9.0, **summarise_episodes(by_hand, 1.0)}
    assert by_hand[0] != by_hand[1]  # two starts, two episodes
    short_env = make_juggle_env(cfg.env, duration=3.0, action_noise=0.05)
    by_hand = summarise_episodes([run_episode(short_env, expert, seed=1000)], 1.0)
    assert record["perturbed"]["short"] == {"duration": 3.0, **by_hand}  # eval.perturbed_seeds


def test_the_final_evaluation_repeats_the_kept_best_instead_of_running_it_again(tmp_path):
    cfg = train_config(
        "~eval.perturbed",
        "+eval.perturbed.shaky={action_noise:0.05}",
        "eval.seeds=1",
        "eval.catch_time=1",
        "eval.perturbed_duration=3",
        "eval.keep_best=true",
    )
    expert = load_policy("expert", make_juggle_env(cfg.env))
    evaluations = Evaluations(cfg)
    with RerunLogger.from_config(cfg.logger, tmp_path) as logger:
        kept = evaluations.evaluate(expert, 10, logger, 6.0)
        evaluations.keep_if_best(kept, _Weights(10))
        evaluations.keep_if_best(evaluations.evaluate(_Idle(), 20, logger, 6.0), _Weights(20))
        assert evaluations.best["frames"] == 10  # the idle actor drops the ball
        final = evaluations.evaluate(_Unplayable(), 30, logger, 6.0, final=True)
        assert final == {**kept, "frames": 30} and evaluations.records[-1] is final
        longer = evaluations.evaluate(expert, 30, logger, 9.0, final=True)  # other episodes
    assert longer["duration"] == 9.0 and longer["mean_throws"] > kept["mean_throws"]


def test_keep_best_prefers_the_actor_that_also_juggles_perturbed(tmp_path):
    evaluations = Evaluations(train_config("eval.keep_best=true"))
    fragile = {"frames": 1, **_summary(54.0), "perturbed": {"noise": _summary(10.0)}}
    tolerant = {"frames": 2, **_summary(50.0), "perturbed": {"noise": _summary(45.0)}}
    evaluations.keep_if_best(tolerant, _Weights(2))
    evaluations.keep_if_best(fragile, _Weights(1))  # later but worse on average: not kept
    assert evaluations.best["frames"] == 2
    assert evaluations.best["score"] == [1.0, 47.5, 120.0]
    assert score(_summary(54.0)) == [1.0, 54.0, 120.0]  # no conditions: the nominal summary


def test_keep_best_ranks_the_nominal_catch_first():
    """Lucky perturbed draws do not lift an actor that drops the ball from the standard start."""
    evaluations = Evaluations(train_config("eval.keep_best=true"))
    juggles = {"frames": 1, **_summary(46.0)}
    juggles["perturbed"] = {
        "noise": _summary(1.0, caught=False),
        "kicks": _summary(1.0, caught=False),
    }
    dropped = {"frames": 2, **_summary(1.0, caught=False)}
    dropped["perturbed"] = {"noise": _summary(50.0), "kicks": _summary(50.0)}
    evaluations.keep_if_best(juggles, _Weights(1))
    evaluations.keep_if_best(dropped, _Weights(2))
    assert evaluations.best["frames"] == 1
    assert score(dropped)[1] > score(juggles)[1]  # it would win on throws alone


def test_a_perturbed_condition_the_env_does_not_know_is_refused_before_training():
    cfg = train_config("+eval.perturbed.windy={gust:1.0}")
    with pytest.raises(ValueError, match="eval.perturbed.windy: env config: .*gust"):
        check_config(cfg)
    cfg = train_config("~eval.perturbed", "+eval.perturbed.noisy={action_noise:0.003,seeds:0}")
    message = "eval.perturbed.noisy.seeds=0 is out of range: expected an integer in [1"
    with pytest.raises(ValueError, match=re.escape(message)):
        check_config(cfg)


def _summary(throws: float, caught: bool = True) -> dict:
    """An evaluation summary of 120-s episodes: caught and up throughout, or dropped at 3 s."""
    return {
        "duration": 120.0,
        "catch_rate": 1.0 if caught else 0.0,
        "mean_throws": throws,
        "mean_time_to_drop": 120.0 if caught else 3.0,
    }


class _Weights:
    """Stands in for an actor: ``keep_if_best`` only copies its ``state_dict``."""

    def __init__(self, tag: int):
        self.tag = tag

    def state_dict(self) -> dict:
        return {"tag": self.tag}


class _Idle:
    """A batch policy that holds the arm still: it drops the ball."""

    acts_on_batches = True

    def reset(self) -> None:
        pass

    def act(self, observations, times, running):
        return np.zeros((len(observations), 3))


class _Unplayable(_Idle):
    """A batch policy that must not be asked to act."""

    def act(self, observations, times, running):
        raise AssertionError("the final evaluation ran episodes it had already run")
