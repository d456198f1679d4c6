"""Staged off-policy runs (algo=apprentice): BC while the teacher acts, DAgger while the student
acts, RL from the cloned actor; each stage's settings, and a run that resumes in any stage."""

import re

import imageio.v3 as iio
import numpy as np
import pytest
import torch
from cli import run_script, train_config
from omegaconf import OmegaConf
from tensordict import TensorDict
from test_offpolicy_training import TINY, train

from jugglerl.offpolicy.stages import StopRule, stages_from_config, stopped_early
from jugglerl.offpolicy.teacher import TEACHER_ACTION
from jugglerl.offpolicy.training import OffPolicyTraining
from jugglerl.policies.loading import load_policy
from jugglerl.runs.checkpoints import load_checkpoint
from jugglerl.training import resume_state
from jugglerl_envs import JuggleEnv

#: Three stages of 128 frames each (+experiment=apprentice_rl), the critic warming up over the RL
#: stage's first batch, which draws a quarter of its samples from the bc stage's demonstrations.
STAGED = [
    *(override for override in TINY if not override.startswith("algo=")),
    "+experiment=apprentice_rl",
    "actor=mlp",
    "collector.total_frames=384",
    "algo.stages.bc.until=128",
    "algo.stages.dagger.until=256",
    "algo.stages.rl.warmup_frames=128",
    "+algo.stages.bc.demonstrations=true",
    "+algo.stages.rl.demo_fraction=0.25",
    "+algo.stages.rl.bc_weight=1.0",
    "algo.stages.bc.optim.updates_per_batch=8",
    "algo.stages.rl.optim.updates_per_batch=8",
    "eval.every_frames=0",
    "eval.perturbed_duration=2",
]


@pytest.mark.slow
def test_the_apprentice_stages_clone_then_dagger_then_rl():
    default = stages_from_config(train_config("algo=apprentice"))
    assert [(s.name, s.end) for s in default] == [("bc", 327680), ("dagger", 368640)]
    bc, dagger, rl = stages_from_config(train_config("+experiment=apprentice_rl"))
    assert [s.name for s in (bc, dagger, rl)] == ["bc", "dagger", "rl"]
    assert (bc.start, bc.end, dagger.end, rl.end) == (0, 327680, 368640, 491520)
    assert bc.cfg.algo.loss == dagger.cfg.algo.loss == "bc" and rl.cfg.algo.loss == "ddpg"
    assert (bc.acts, bc.noise, dagger.acts, dagger.noise) == ("teacher", 0.003, "student", 0.0)
    assert (rl.acts, rl.noise) == ("student", 0.003) and "exploration" not in bc.cfg
    assert not bc.demonstrations and rl.demo_fraction == 0  # no stage draws on demonstrations
    assert bc.cfg.optim.trains == dagger.cfg.optim.trains == "base"
    assert rl.cfg.optim.trains == "correction" and rl.cfg.actor.correction.max_correction == 0.002
    assert rl.cfg.algo.n_steps == 10 and bc.cfg.algo.n_steps == 1 and rl.cfg.algo.gamma == 0.99
    # the rl stage's envs are split among the nominal one and each evaluated perturbation
    # (a condition's number of evaluation episodes is no env argument)
    conditions = [dict(c) for c in rl.cfg.eval.perturbed.values()]
    assert conditions[2] == {"action_noise": 0.003, "seeds": 6}
    assert rl.variants == ({}, *[{k: v for k, v in c.items() if k != "seeds"} for c in conditions])
    assert bc.variants == dagger.variants == ({},) and len(rl.variants) == 5
    assert bc.cfg.optim.lr_actor == 1e-3 and dagger.cfg.optim.lr_actor == 1e-4
    assert rl.cfg.optim.lr_actor == 1e-5 and rl.cfg.optim.lr_critic == 3e-4
    assert bc.cfg.optim.updates_per_batch == 256 and dagger.cfg.optim.updates_per_batch == 64
    assert rl.cfg.optim.updates_per_batch == 128 and rl.cfg.algo.bc_tau == 0.001
    assert rl.actor_frozen(rl.start + 61440) and not rl.actor_frozen(rl.start + 61441)
    td3 = train_config("+experiment=apprentice_rl", "algo.stages.rl.loss=td3")
    assert stages_from_config(td3)[2].cfg.algo.loss == "td3"
    short = train_config("+experiment=apprentice_rl", "collector.total_frames=340000")
    assert [(s.name, s.end) for s in stages_from_config(short)] == [
        ("bc", 327680),
        ("dagger", 340000),
    ]
    (alone,) = stages_from_config(train_config("+experiment=finetune"))  # null stages do not run
    assert (alone.name, alone.start, alone.end) == ("rl", 0, 122880)


def test_the_default_run_composes_no_critic_and_no_correction():
    """The rl stage's networks and settings come with +experiment=apprentice_rl alone."""
    cfg = train_config()
    assert "critic" not in cfg and "lr_critic" not in cfg.optim and "correction" not in cfg.actor
    assert "gamma" not in cfg.algo and list(cfg.algo.stages) == ["bc", "dagger"]


def test_plain_train_py_composes_the_quickstarts_lstm_apprentice():
    plain, quickstart = train_config(), train_config("actor=lstm")
    assert OmegaConf.to_yaml(plain) == OmegaConf.to_yaml(quickstart)
    assert plain.algo.name == "apprentice" and plain.actor.name == "lstm"
    assert train_config("actor=mlp").actor.name == "mlp"  # the command line still chooses
    assert train_config("algo=ddpg").actor.name == "mlp"  # and the other algorithms keep theirs


def test_a_run_without_stages_is_one_stage_of_its_loss():
    (stage,) = stages_from_config(train_config("algo=td3"))
    assert (stage.name, stage.start, stage.end, stage.cfg.algo.loss) == ("td3", 0, 307200, "td3")
    assert stage.acts is None and stage.cfg.exploration.name == "gaussian"  # the group explores
    assert not stage.actor_frozen(1024) and stage.demo_fraction == 0


@pytest.mark.parametrize(
    "override, message",
    [
        ("algo.stages.dagger.until=100", "algo.stages.dagger.until=100 must be above"),
        ("+algo.stages.bc.epochs=3", "algo.stages.bc: unknown keys ['epochs']"),
        ("algo.stages.rl.demo_fraction=1", "algo.stages.rl.demo_fraction=1.0 must be in [0, 1)"),
        ("algo.stages.rl.n_steps=0", "algo.stages.rl.n_steps=0 must be >= 1"),
        ("algo.stages.rl.perturbed=3", "algo.stages.rl.perturbed must map names to env"),
        (
            "algo.stages.bc.demonstrations=false",
            "a demo_fraction needs a stage with demonstrations",
        ),
        ("algo.stages.bc.acts=watcher", "algo.stages.bc.acts=watcher must be one of teacher, stud"),
        ("algo.stages.dagger.noise=-0.1", "algo.stages.dagger.noise=-0.1 must be a number >= 0"),
        ("optim.lr_actor=-1", "optim.lr_actor=-1 is out of range"),  # each stage sets its own
        ("optim.updates_per_batch=-1", "optim.updates_per_batch=-1 is out of range"),
        ("algo.stages.rl.noise=loud", "algo.stages.rl.noise=loud must be a number >= 0"),
        (
            "+algo.stages.rl.exploration.sigma_init=0.01",
            "algo.stages.rl: a stage with acts does not explore (exploration keys given)",
        ),
        ("teacher.policy=null", "algo.stages.bc.acts=teacher needs a teacher.policy"),
        (
            "~algo.stages.dagger.acts",
            "algo.stages.dagger.noise is the σ of who acts: it needs algo.stag",
        ),
    ],
)
def test_bad_stage_settings_are_named(override, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        stages_from_config(
            train_config(
                "+experiment=apprentice_rl",
                "+algo.stages.bc.demonstrations=true",
                "+algo.stages.rl.demo_fraction=0.25",
                override,
            )
        )


def test_stages_are_named_settings_and_a_bad_shape_is_named():
    listed = train_config("algo=apprentice")
    listed.algo.stages = [{"until": 128}]
    with pytest.raises(ValueError, match=re.escape("algo.stages must map stage names to their")):
        stages_from_config(listed)
    scalar = train_config("algo=apprentice")
    scalar.algo.stages.dagger = 3
    with pytest.raises(ValueError, match=re.escape("algo.stages.dagger must map setting names")):
        stages_from_config(scalar)


def test_a_stage_whose_loss_lacks_its_settings_is_named_as_the_run_starts():
    def problem(*overrides):
        with pytest.raises(ValueError) as error:
            stages_from_config(train_config(*overrides))
        return str(error.value)

    assert problem("+algo.stages.rl={loss: ddpg, acts: student}").startswith(
        "algo.stages.rl: algo.loss=ddpg needs critic, optim.lr_critic, optim.weight_decay,"
        " algo.gamma, algo.tau (configs/critic.yaml"
    )
    assert problem("+algo.stages.rl={loss: sac, acts: student}").startswith(
        "algo.stages.rl: algo.loss='sac' is not available; choose one of bc, ddpg, td3"
    )
    assert problem("algo.bc_tau=1.5") == "algo.stages.bc: algo.bc_tau=1.5 must be in (0, 1] or null"
    assert problem("algo=td3", "algo.policy_delay=0") == "algo.policy_delay=0 must be >= 1"
    assert problem("algo=bc", "algo.stages.bc.acts=student", "teacher.policy=null") == (
        "algo.stages.bc: algo.loss=bc clones a teacher in the loop: set teacher.policy"
    )


@pytest.mark.slow
def test_a_staged_run_lets_the_teacher_act_then_the_student_and_resumes_in_any_stage(
    tmp_path, capsys
):
    cfg = train_config(*STAGED)
    cfg.collector.total_frames = 256  # stop after the DAgger stage
    metrics, training = train(cfg, tmp_path / "run")
    assert [h["stage"] for h in metrics["history"]] == [0, 1]
    data = training.buffer._buffer[:]  # the frames of both stages, in order
    bc_frames, dagger_frames = data[:128], data[128:256]
    # BC: the teacher acts (white noise of σ = 0.003 around it); DAgger: the actor acts
    assert (bc_frames["action"] - bc_frames[TEACHER_ACTION]).std() == pytest.approx(0.003, rel=0.2)
    assert not torch.allclose(dagger_frames["action"], dagger_frames[TEACHER_ACTION], atol=1e-3)
    assert len(training.demonstrations) == 128  # only the BC stage's frames
    state = load_checkpoint(tmp_path / "run")
    assert state["counters"]["frames"] == 256

    cfg.collector.total_frames = 384
    resumed = OffPolicyTraining(cfg, tmp_path / "run", state)
    assert "note:" not in capsys.readouterr().err  # nothing lost: the buffers reopen
    assert (len(resumed.buffer), len(resumed.demonstrations)) == (256, 128)
    assert resumed.stage.name == "dagger"  # where it was saved; the run moves on from there
    for key, value in training.actor.state_dict().items():  # the cloned actor carries over
        torch.testing.assert_close(resumed.actor.state_dict()[key], value)
    # the RL stage starts from the actor DAgger deploys: its moving average (algo.bc_tau)
    actor = {k: v.clone() for k, v in resumed.current_actor().state_dict().items()}
    resumed.close()
    metrics, again = train(cfg, tmp_path / "run", state)
    assert [h["stage"] for h in metrics["history"]] == [0, 1, 2]
    assert again.stage.name == "rl" and type(again.update).__name__ == "DDPG"
    assert "loss_critic" in metrics["history"][-1] and "loss_bc" in metrics["history"][-1]
    for key, value in again.actor.state_dict().items():  # the warm-up kept the actor still
        torch.testing.assert_close(value, actor[key])
    again.close()


@pytest.mark.slow
def test_the_default_pipeline_trains_only_the_correction_in_rl_and_resumes_inside_it(tmp_path):
    """BC, DAgger, then two batches of residual RL (no warm-up), killed after the first: the
    resume continues inside the rl stage, the clone under the correction never moves, the
    correction does."""
    cfg = train_config(
        *STAGED,
        "algo.stages.rl.warmup_frames=0",
        "actor=lstm",
        "replay_buffer.slice_len=16",
        "algo.stages.rl.optim.lr_actor=1e-2",
    )
    cfg.collector.total_frames = 384  # stop after the first rl batch
    _, first = train(cfg, tmp_path / "run")
    assert first.stage.name == "rl" and first.stage.cfg.optim.trains == "correction"
    state = load_checkpoint(tmp_path / "run")
    assert state["stage"] == 2 and state["counters"]["frames"] == 384

    cfg.collector.total_frames = 512
    metrics, again = train(cfg, tmp_path / "run", state)
    assert [h["stage"] for h in metrics["history"]] == [0, 1, 2, 2]
    assert again.stage.name == "rl" and again.frames == 512
    weights = again.actor.state_dict()
    corrections = [k for k in weights if k.startswith("module.2.")]  # lstm, head, correction
    assert corrections
    for key, value in state["actor"].items():
        if key not in corrections:  # the clone under the correction
            assert torch.equal(weights[key], value), key
    assert any(not torch.equal(weights[k], state["actor"][k]) for k in corrections)
    again.close()


@pytest.mark.slow
def test_a_resume_with_a_stage_override_runs_td3_in_the_rl_stage(tmp_path):
    """A resume's override of a stage's key reaches that stage."""
    cfg = train_config(*STAGED)
    cfg.collector.total_frames = 256  # stop after the DAgger stage
    train(cfg, tmp_path / "run")
    overrides = ["collector.total_frames=384", "algo.stages.rl.loss=td3"]
    resumed, run_dir, state = resume_state(
        str(tmp_path / "run"), train_config(*STAGED, *overrides), overrides
    )
    assert resumed.algo.stages.rl.loss == "td3" and resumed.collector.total_frames == 384
    metrics, again = train(resumed, run_dir, state)
    assert again.stage.name == "rl" and type(again.update).__name__ == "TD3"
    again.close()


@pytest.mark.slow
def test_a_stage_starts_from_the_average_the_stage_before_deploys(tmp_path):
    cfg = train_config(*STAGED, "algo.bc_tau=0.5", "algo.stages.dagger.optim.updates_per_batch=0")
    cfg.collector.total_frames = 128  # the BC stage alone
    _, training = train(cfg, tmp_path / "run")
    average = training.update.target_actor().state_dict()
    online = training.actor.state_dict()
    assert any(not torch.equal(average[k], online[k]) for k in online)
    training.close()
    cfg.collector.total_frames = 256  # resumed into DAgger, which does not update here
    _, again = train(cfg, tmp_path / "run", load_checkpoint(tmp_path / "run"))
    assert again.stage.name == "dagger"
    for key, value in again.actor.state_dict().items():
        torch.testing.assert_close(value, average[key])
    again.close()


def test_the_rl_stage_samples_its_demo_fraction_from_the_demonstrations(tmp_path):
    cfg = train_config(*STAGED)
    training = OffPolicyTraining(cfg, tmp_path)
    training._enter(training.stages[2])
    marked = torch.arange(256).unsqueeze(-1)
    training.buffer.extend(TensorDict({"mark": marked}, [256]))
    training.demonstrations.extend(TensorDict({"mark": -1 - marked}, [256]))
    batch = training._sample()
    assert batch.shape == (64,) and int((batch["mark"] < 0).sum()) == 16  # 0.25 of 64
    training.close()


@pytest.mark.slow
def test_plot_learning_draws_a_runs_evaluations_and_names_a_missing_run(tmp_path):
    cfg = train_config(*STAGED, "eval.every_frames=128")
    train(cfg, tmp_path / "run")
    result = run_script("plot_learning.py", str(tmp_path / "run"), "--out", str(tmp_path / "c.png"))
    assert result.returncode == 0, result.stderr
    image = iio.imread(tmp_path / "c.png")
    assert image.shape[1] > 1000 and len(np.unique(image.reshape(-1, image.shape[-1]), axis=0)) > 50
    missing = run_script("plot_learning.py", str(tmp_path / "nowhere"))
    assert missing.returncode == 1
    assert (
        missing.stderr.strip()
        == f"error: no metrics.json in {tmp_path / 'nowhere'} (a finished off-policy run directory)"
    )


TEACHERS = ("closed_loop", "closed_loop_gains")


@pytest.mark.slow
def test_the_phase_features_follow_the_teachers_cycle_and_a_resume_keeps_the_checkpoints(tmp_path):
    """``state.period: teacher`` (the apprentice default) is the teacher's command cycle, resolved
    when the run starts; a resume with another teacher keeps the number its checkpoint holds."""
    env = JuggleEnv()
    closed_loop, gains = (load_policy(name, env).command for name in TEACHERS)
    assert closed_loop.cycle != gains.cycle
    cfg = train_config(*STAGED)
    assert cfg.state.period == "teacher"
    cfg.collector.total_frames = 128
    _, training = train(cfg, tmp_path / "run")
    assert training.cfg.state.period == closed_loop.cycle
    other = ["teacher.policy=closed_loop_gains"]
    another = OffPolicyTraining(train_config(*STAGED, *other), tmp_path / "another")
    assert another.cfg.state.period == gains.cycle
    another.close()

    overrides = [*other, "collector.total_frames=256"]
    resumed, run_dir, state = resume_state(
        str(tmp_path / "run"), train_config(*STAGED, *overrides), overrides
    )
    assert (
        resumed.state.period == closed_loop.cycle and resumed.teacher.policy == "closed_loop_gains"
    )
    assert state["config"]["state"]["period"] == closed_loop.cycle


#: The earth pipeline (``+experiment=earth_apprentice``) with one 32-step batch per stage: four
#: envs, so that the dagger stage's nominal, weaker and stronger arms and offset start get one each.
EARTH_STAGED = [
    *(override for override in TINY if not override.startswith("algo=")),
    "+experiment=earth_apprentice",
    "actor=mlp",
    "env.duration=8",  # the teacher throws 4 times: enough to time its cycle
    "collector.num_envs=4",
    "collector.frames_per_batch=128",
    "checkpoint_every_frames=128",
    "algo.stages.bc.until=128",
    "eval.every_frames=0",
    "eval.perturbed_duration=2",
]


@pytest.mark.slow
def test_the_earth_pipeline_clones_earth_juggler_with_three_arms_and_resumes_in_dagger(tmp_path):
    cfg = train_config(*EARTH_STAGED)
    bc, dagger = stages_from_config(cfg)
    arms = ({}, {"servo_gain": 0.95}, {"servo_gain": 1.05})
    assert bc.variants == arms and dagger.variants == (*arms, {"reset_noise": 0.01})
    assert "weak_arm" in cfg.eval.perturbed
    cfg.collector.total_frames = 128
    _, training = train(cfg, tmp_path / "run")
    frames = training.buffer._buffer[:128]  # the teacher acts with its wider noise
    assert (frames["action"] - frames[TEACHER_ACTION]).std() == pytest.approx(0.01, rel=0.2)
    period = training.cfg.state.period  # earth_juggler's time between throws, not a command's
    assert 1.6 < period < 2.0
    state = load_checkpoint(tmp_path / "run")
    assert state["stage"] == 0 and state["counters"]["frames"] == 128

    cfg.collector.total_frames = 256
    metrics, again = train(cfg, tmp_path / "run", state)
    assert [h["stage"] for h in metrics["history"]] == [0, 1] and again.stage.name == "dagger"
    assert again.cfg.state.period == period and again.frames == 256
    again.close()


# --- early stops --------------------------------------------------------------------------------
def evaluation(frames: int, throws: float, caught: float = 1.0, perturbed: float | None = None):
    """A hand-made evaluation record of 120-s nominal episodes (and one 30-s condition)."""
    record = {"frames": frames, "duration": 120.0, "catch_rate": caught}
    record |= {"mean_throws": throws, "mean_time_to_drop": 120.0 * caught}
    if perturbed is not None:
        condition = {"duration": 30.0, "mean_throws": perturbed, "mean_time_to_drop": 30.0}
        record["perturbed"] = {"kicks": condition}
    return record


def test_a_stop_rule_ends_a_stage_on_its_target_or_when_evaluations_stop_improving():
    target = StopRule(throws=52)
    assert target.reason([evaluation(1, 51)]) is None
    assert target.reason([evaluation(1, 60, caught=0.0)]) is None  # the ball must be caught
    assert "scored 52.0 throws (stop.throws=52)" in target.reason([evaluation(1, 52)])
    # perturbed throws count as over the nominal length: (56 + 4 * 11) / 2 = 50, then 52
    assert target.reason([evaluation(1, 56, perturbed=11)]) is None
    assert target.reason([evaluation(1, 56, perturbed=12)]) is not None
    patient = StopRule(patience=2)
    history = [evaluation(1, 10), evaluation(2, 30), evaluation(3, 29)]
    assert patient.reason(history) is None  # one evaluation since the best
    assert "2 evaluations without a better one" in patient.reason([*history, evaluation(4, 30)])
    assert patient.reason([*history, evaluation(4, 31)]) is None


def test_a_stage_that_stops_early_moves_the_later_ones_and_keeps_their_lengths():
    stages = stages_from_config(train_config("+experiment=apprentice_rl"))
    bc, dagger, rl = stopped_early(stages, {0: 81920})
    assert (bc.start, bc.end) == (0, 81920)
    assert (dagger.start, dagger.end) == (81920, 81920 + 40960)
    assert rl.end - rl.start == stages[2].end - stages[2].start and dagger.end == rl.start
    bc, dagger, rl = stopped_early(stages, {0: 81920, 1: 102400})
    assert (dagger.end, rl.start, rl.end) == (102400, 102400, 102400 + 491520 - 368640)


@pytest.mark.parametrize(
    "stop, message",
    [
        ("{throws: 0}", "algo.stages.bc.stop.throws=0 is out of range"),
        ("{patience: 0}", "algo.stages.bc.stop.patience=0 is out of range"),
        ("{throws: 52, after: 3}", "algo.stages.bc.stop: a mapping of throws and/or patience"),
        ("3", "algo.stages.bc.stop: a mapping of throws and/or patience"),
    ],
)
def test_bad_stop_rules_are_named(stop, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        stages_from_config(train_config("algo=apprentice", f"algo.stages.bc.stop={stop}"))


#: BC evaluated after every batch of 128 frames and told to stop at its second evaluation that
#: is no better than its first (an untrained actor's evaluations tie at zero throws).
STOPPING = [
    *STAGED,
    "collector.total_frames=1280",
    "algo.stages.bc.until=1024",
    "algo.stages.dagger.until=1152",
    "eval.every_frames=128",
    "eval.seeds=1",
    "algo.stages.bc.stop={patience: 1}",
]


@pytest.mark.slow
def test_an_early_stop_ends_the_stage_between_batches_and_a_resume_goes_on_to_the_next(
    tmp_path, monkeypatch, capsys
):
    cfg = train_config(*STOPPING)
    metrics, training = train(cfg, tmp_path / "whole")
    # BC stops at its second evaluation (frame 256); DAgger keeps its 128 frames, the RL stage
    # its 128: the run ends 768 frames early
    stages = [(h["frames"], h["stage"]) for h in metrics["history"]]
    assert stages == [(128, 0), (256, 0), (384, 1), (512, 2)]
    assert metrics["frames"] == 512 and training.stops == {0: 256}
    assert "note: stage bc ends at frame 256, 768 frames early" in capsys.readouterr().err
    assert set(metrics["seconds"]["stages"]) == {"bc", "dagger", "rl"}
    assert {"collect", "update", "evaluate", "checkpoint"} <= set(metrics["seconds"]["parts"])

    saved = OffPolicyTraining.save

    def killed_after_the_stop(self):  # the run dies right after the stop's checkpoint
        saved(self)
        if self.stops:
            raise KeyboardInterrupt

    monkeypatch.setattr(OffPolicyTraining, "save", killed_after_the_stop)
    with pytest.raises(KeyboardInterrupt):
        train(cfg, tmp_path / "killed")
    monkeypatch.setattr(OffPolicyTraining, "save", saved)
    state = load_checkpoint(tmp_path / "killed")
    assert state["counters"]["frames"] == 256 and state["stopped_early"] == {0: 256}
    resumed, again = train(cfg, tmp_path / "killed", state)
    assert [(h["frames"], h["stage"]) for h in resumed["history"]] == stages
    assert again.stage.name == "rl" and resumed["frames"] == 512
