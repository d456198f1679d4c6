"""The real rerun viewer (headless) opens each recording on its run: every view shown has data.

One screenshot takes several seconds of CPU, so there is one per kind of recording: an
``evaluate.py`` episode and a short ``train.py`` run. The PNGs stay in pytest's temporary
folder (``pytest --basetemp=DIR`` keeps them where you want to look at them).
"""

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from cli import run_script, run_train
from viewer import opening_views, screenshot, shows, views_without_data

from jugglerl.recording.blueprint import episode_blueprint, offpolicy_curves, training_blueprint
from jugglerl.recording.names import EVAL, SIM_TIME, STEP, TRAIN
from jugglerl.recording.reading import entities

#: About 7 s on 2 cores: two batches of 128 frames, episodes of 1 s, so that training episodes
#: finish (return, throws) and two evaluations (each recorded) happen.
SHORT_DDPG = [
    "algo=ddpg",
    "collector.num_envs=2",
    "collector.frames_per_batch=128",
    "collector.total_frames=256",
    "env.duration=1",
    "eval.every_frames=128",
    "eval.seeds=1",
    "eval.duration=2",
    "eval.catch_time=1",
    "state.norm_frames=200",
    "replay_buffer.batch_size=64",
    "optim.updates_per_batch=4",
    "checkpoint_every_frames=256",
    "progress=false",
    "+eval.perturbed.shaky={action_noise:0.01}",  # its throws get a panel of their own
    "eval.perturbed_duration=1",
]


def check_opening(recording: Path, out: Path, blueprint, timeline: str) -> dict:
    """Check that the views ``blueprint`` opens with have data on ``timeline`` (from the file),
    then screenshot ``recording`` as it opens: the viewer shows that layout on that timeline,
    and no view reports an error."""
    expected = opening_views(blueprint)
    assert views_without_data(recording, expected, timeline) == []
    state = screenshot(recording, out)
    assert state["recordings"][0]["current_timeline"] == timeline
    shown = {view["name"] for view in state["views"]}
    assert {str(view.name) for view in expected} <= shown, "the viewer shows another layout"
    assert [(v["name"], v["reports"]) for v in state["views"] if v["reports"]] == []
    image = iio.imread(out)
    assert image.shape[:2] == (1000, 1600)  # the tool's default SIZE
    assert len(np.unique(image.reshape(-1, image.shape[-1]), axis=0)) > 200  # not a blank window
    return state


@pytest.mark.slow
def test_an_evaluated_episode_opens_on_sim_time_with_every_view_showing_data(tmp_path):
    result = run_script(
        "evaluate.py", "policy=closed_loop", "duration=20", f"hydra.run.dir={tmp_path}"
    )
    assert result.returncode == 0, result.stderr
    check_opening(
        tmp_path / "episode.rrd", tmp_path / "episode.png", episode_blueprint(1.0), SIM_TIME
    )


@pytest.mark.slow
def test_a_training_run_opens_on_its_learning_curves_with_every_view_showing_data(tmp_path):
    result = run_train(*SHORT_DDPG, f"hydra.run.dir={tmp_path}")
    assert result.returncode == 0, result.stderr
    names = entities(tmp_path / "train.rrd")
    metrics = {name for name in names if name.count("/") == 1}
    metrics |= {name for name in names if name.startswith(f"{EVAL}/shaky/")}
    blueprint = training_blueprint(offpolicy_curves(["shaky"]))
    views = opening_views(blueprint)
    in_no_panel = {
        name
        for name in metrics
        if name.split("/")[0] in (TRAIN, EVAL) and not any(shows(view, name) for view in views)
    }
    # only the frame count, which is the step itself, and the condition's other summaries
    assert in_no_panel == {f"{TRAIN}/frames"} | {
        f"{EVAL}/shaky/{key}" for key in ("catch_rate", "mean_catches", "mean_time_to_drop")
    }
    state = check_opening(tmp_path / "train.rrd", tmp_path / "train.png", blueprint, STEP)
    step = next(t for t in state["recordings"][0]["timelines"] if t["name"] == STEP)
    assert (step["start"], step["end"]) == (128, 256)  # the whole run is on the timeline
