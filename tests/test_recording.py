"""Recordings read back with rerun's own reader: the logger, the episode recorder, evaluate.py."""

import json
import socket
import subprocess
import sys
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
import rerun_cli
from rerun.chunk import RrdReader
from test_evaluate_script import run_evaluate

from jugglerl.batch.episodes import batch_policy, run_episodes
from jugglerl.commands import load_command
from jugglerl.policies.command import CommandPolicy
from jugglerl.policies.episodes import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl.recording.episode import BatchEnvRecorder, EpisodeRecorder
from jugglerl.recording.logger import RerunLogger, has_footer
from jugglerl.recording.reading import column, entities, timelines
from jugglerl.runs.files import RunFileError
from jugglerl_envs import JuggleBatch, JuggleEnv
from jugglerl_envs.events import count_throws

RERUN_CLI = Path(sys.executable).parent / "rerun"
#: The viewer/server binary itself: the ``rerun`` entry point above is a Python process that
#: starts it as a child, so ending the entry point would leave the server running.
RERUN_BINARY = Path(rerun_cli.__file__).parent / "rerun"
SCALAR = ("Scalars:scalars", "step")


def verify(path: Path) -> None:
    """rerun's own check that the file is complete and decodes."""
    result = subprocess.run([str(RERUN_CLI), "rrd", "verify", str(path)], capture_output=True)
    assert result.returncode == 0, result.stderr.decode()


# --- RerunLogger ---------------------------------------------------------------------------
def test_a_recording_left_without_its_footer_is_a_failed_write(tmp_path):
    """rerun's writer does not report a footer it could not write (a disk full at the end)."""
    logger = RerunLogger("train", tmp_path)
    logger.log_scalar("x", 1.0, step=0)
    close = logger._close_at_exit

    def close_and_lose_the_footer():
        close()
        logger.path.write_bytes(logger.path.read_bytes()[:-8])

    logger._close_at_exit = close_and_lose_the_footer
    with pytest.raises(RunFileError, match=r"train.rrd: could not write the recording \(its foot"):
        logger.shutdown()
    with RerunLogger("whole", tmp_path) as whole:
        whole.log_scalar("x", 1.0, step=0)
    assert has_footer(whole.path)


@pytest.mark.parametrize("flush_every", [0.0, 60.0])  # a send per value, or one at shutdown
def test_scalars_of_a_training_loop_are_all_there_with_their_steps(tmp_path, flush_every):
    steps = list(range(0, 2000, 100))
    with RerunLogger("train", tmp_path, flush_every=flush_every) as logger:
        logger.log_hparams({"optim": {"lr": 0.001}, "seed": 3})
        for step in steps:
            logger.log_metrics({"train/return": step / 10, "train/loss": 1 / (1 + step)}, step)
        logger.log_scalar("eval/throws", 12, step=1900)
        logger.log_histogram("train/actions", np.linspace(-1, 1, 101), step=1900, bins=4)
    verify(logger.path)
    times, values = column(logger.path, "train/return", "Scalars:scalars", "step")
    assert times.tolist() == steps and values.tolist() == [s / 10 for s in steps]
    times, values = column(logger.path, "train/loss", "Scalars:scalars", "step")
    assert times.tolist() == steps and np.allclose(values, [1 / (1 + s) for s in steps])
    assert column(logger.path, "eval/throws", "Scalars:scalars", "step")[1].tolist() == [12.0]
    times, bars = column(logger.path, "train/actions", "BarChart:values", "step")
    assert times.tolist() == [1900] and sum(bars[0]["buffer"]) == 101  # all samples binned
    text = column(logger.path, "hparams", "TextDocument:text")[1][0]
    assert "lr: 0.001" in text and "seed: 3" in text


def test_scalars_without_a_step_take_the_last_one(tmp_path):
    with RerunLogger("train", tmp_path) as logger:
        logger.log_scalar("train/a", 1.0, step=7)
        logger.log_scalar("train/b", 2.0)
    assert column(logger.path, "train/b", "Scalars:scalars", "step")[0].tolist() == [7]


@pytest.mark.parametrize("interruption", [RuntimeError, KeyboardInterrupt])
def test_a_run_interrupted_by_an_exception_leaves_a_readable_file(tmp_path, interruption):
    logger = RerunLogger("train", tmp_path, flush_every=60.0)
    with pytest.raises(interruption), logger:
        logger.log_scalar("train/return", 5.0, step=10)
        raise interruption()
    verify(logger.path)
    assert column(logger.path, "train/return", "Scalars:scalars", "step")[1].tolist() == [5.0]


@pytest.mark.slow
def test_a_crashed_script_without_a_with_block_still_closes_its_file(tmp_path):
    script = (
        "from jugglerl.recording.logger import RerunLogger\n"
        f"logger = RerunLogger('train', {str(tmp_path)!r}, flush_every=60.0)\n"
        "logger.log_scalar('train/return', 5.0, step=10)\n"
        "logger.flush()\n"
        "raise SystemExit('crash')\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert result.returncode != 0 and "crash" in result.stderr
    verify(tmp_path / "train.rrd")
    assert column(tmp_path / "train.rrd", "train/return", "Scalars:scalars", "step")[1] == [5.0]


def test_an_existing_recording_is_never_overwritten(tmp_path):
    for _ in range(2):
        with RerunLogger("episode", tmp_path) as logger:
            logger.log_scalar("eval/throws", 1.0, step=0)
    assert sorted(p.name for p in tmp_path.glob("*.rrd")) == ["episode.1.rrd", "episode.rrd"]


def test_video_frames_are_logged_as_images(tmp_path):
    video = np.zeros((3, 3, 8, 6), dtype=np.uint8)  # [T, C, H, W]
    with RerunLogger("train", tmp_path) as logger:
        logger.log_video("eval/video", video, step=4)
    times, _ = column(logger.path, "eval/video", "Image:buffer", "video_frame")
    assert times.tolist() == [0, 1, 2]
    assert column(logger.path, "eval/video", "Image:format", "step")[0].tolist() == [4] * 3


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def listening(port: int) -> bool:
    with socket.socket() as probe:
        return probe.connect_ex(("127.0.0.1", port)) == 0


def returns_written(path: Path) -> list[float]:
    """The ``train/return`` values in an ``.rrd`` file that a server may still be writing."""
    if not path.exists():
        return []
    try:
        return column(path, "train/return", *SCALAR)[1].ravel().tolist()
    except (RuntimeError, ValueError):  # the server has not yet written a whole recording
        return []


def test_live_url_also_streams_to_a_running_viewer_server(tmp_path):
    port = free_port()
    received = tmp_path / "received.rrd"
    server = subprocess.Popen(
        [str(RERUN_BINARY), "--port", str(port), "--save", str(received)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 20
        while not listening(port):
            assert time.monotonic() < deadline, "the rerun server did not start"
            time.sleep(0.1)
        url = f"rerun+http://127.0.0.1:{port}/proxy"
        with RerunLogger("train", tmp_path / "run", live_url=url) as logger:
            logger.log_scalar("train/return", 7.0, step=3)
        while not returns_written(received):
            assert time.monotonic() < deadline, "nothing reached the live server"
            time.sleep(0.1)
    finally:
        end(server)
    assert not listening(port), "the server this test started is still running"
    assert column(received, "train/return", *SCALAR)[1].tolist() == [7.0]
    assert column(logger.path, "train/return", *SCALAR)[1].tolist() == [7.0]  # and the file


def end(process: subprocess.Popen, grace: float = 10.0) -> None:
    """Stop ``process`` (SIGTERM, then SIGKILL after ``grace`` seconds) and reap it."""
    process.terminate()
    try:
        process.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(timeout=grace)


# --- EpisodeRecorder -----------------------------------------------------------------------
def record_expert(
    tmp_path: Path, duration: float, scene_fps: float = 50.0, root: str = "", balls: int = 1
):
    """Record the expert; return the logger path, the metrics and the true ball trajectory."""
    env = JuggleEnv(duration=duration, balls=balls)
    trajectory = []

    class Tracing(CommandPolicy):
        def act(self, observation, time):
            trajectory.append((time, *observation[6:9]))
            return super().act(observation, time)

    with RerunLogger("episode", tmp_path) as logger:
        recorder = EpisodeRecorder(env, logger.recording, root=root, scene_fps=scene_fps)
        metrics = run_episode(recorder, Tracing(load_command("expert")), seed=0)
    return logger.path, metrics, np.array(trajectory)


def test_an_episode_recording_holds_the_scene_and_the_plots(tmp_path):
    path, _, _ = record_expert(tmp_path, duration=4.0)
    verify(path)
    names = entities(path)
    assert {"world/ball", "plots/ball_height", "plots/threshold", "world/threshold"} <= names
    model = JuggleEnv().model
    geoms = {model.geom(g).name for g in range(model.ngeom)}
    assert geoms == {name.rsplit("/", 1)[-1] for name in names if name.rsplit("/", 1)[-1] in geoms}
    cup = [name for name in names if name.endswith("/cup")]
    assert cup == [
        "world/base/shoulder_link/upper_arm_link/forearm_link/wrist_1_link/"
        "wrist_2_link/wrist_3_link/cup"
    ]  # paths mirror the body tree
    assert "sim_time" in timelines(path)


def test_logged_ball_positions_match_the_simulated_trajectory(tmp_path):
    path, metrics, trajectory = record_expert(tmp_path, duration=6.0)
    times, positions = column(path, "world/ball", "Transform3D:translation", "sim_time")
    # every env step is a frame at 50 Hz; the policy saw each state before acting on it
    assert len(times) == len(trajectory) + 1  # + the last state, which no policy sees
    assert np.allclose(times[:-1], trajectory[:, 0], atol=1e-9)
    assert np.allclose(positions[:-1], trajectory[:, 1:], atol=1e-6)  # float32


def test_an_env_of_a_batch_records_the_same_episode_as_a_lone_env(tmp_path):
    """Evaluations record their first episode while the batch runs all of them."""
    expert = load_command("expert")
    lone, _, _ = record_expert(tmp_path / "lone", duration=6.0)
    batch = JuggleBatch(3, autoreset=False, duration=6.0, reset_noise=[0.0, 0.01, 0.01])
    with RerunLogger("episode", tmp_path / "batch") as logger:
        recorder = BatchEnvRecorder(batch, 0, logger.recording, "")
        policies = batch_policy(CommandPolicy(expert), 3)
        (metrics, *_) = run_episodes(batch, policies, [0, 1, 2], recorder)
    verify(logger.path)
    for entity, component in (
        ("world/ball", "Transform3D:translation"),
        ("plots/ball_height", "Scalars:scalars"),
        ("plots/throws", "Scalars:scalars"),
    ):
        times, values = column(lone, entity, component, "sim_time")
        batch_times, batch_values = column(logger.path, entity, component, "sim_time")
        assert np.array_equal(batch_times, times) and np.array_equal(batch_values, values)
    assert len(column(logger.path, "plots/throws", "Scalars:scalars", "sim_time")[0]) == (
        metrics.throws
    )


def test_an_abandoned_episode_keeps_what_was_recorded(tmp_path, hold):
    """Ctrl-C in evaluate.py closes the recorder mid-episode: the samples so far are sent."""
    env = JuggleEnv()
    with RerunLogger("episode", tmp_path) as logger:
        recorder = EpisodeRecorder(env, logger.recording)
        recorder.reset(seed=0)
        for _ in range(30):
            recorder.step(hold(env))
        recorder.close()
    times, _ = column(logger.path, "plots/ball_height", "Scalars:scalars", "sim_time")
    assert len(times) == 31 and times[-1] == pytest.approx(0.6)


def test_scene_frames_follow_scene_fps_not_the_physics(tmp_path):
    path, _, _ = record_expert(tmp_path, duration=4.0, scene_fps=10.0)
    frame_times, _ = column(path, "world/ball", "Transform3D:translation", "sim_time")
    assert np.allclose(frame_times, np.arange(41) * 0.1)
    heights_at, _ = column(path, "plots/ball_height", "Scalars:scalars", "sim_time")
    assert len(heights_at) == 201  # the height stays at the env's 50 Hz


def test_throw_markers_and_heights_agree_with_the_env(tmp_path):
    path, metrics, _ = record_expert(tmp_path, duration=12.0, root="eval/episodes/0001")
    _, heights = column(path, "eval/episodes/0001/plots/ball_height", "Scalars:scalars", "sim_time")
    crossings = count_throws(heights, np.ones_like(heights, dtype=bool), threshold=1.0)
    marker_times, marker_heights = column(
        path, "eval/episodes/0001/plots/throws", "Scalars:scalars", "sim_time"
    )
    assert metrics.throws >= 3
    assert crossings == len(marker_times) == metrics.throws
    assert (marker_heights >= 1.0).all()


def test_two_ball_throw_markers_sit_on_the_ball_thrown(tmp_path):
    env = JuggleEnv(duration=8.0, balls=2)
    with RerunLogger("episode", tmp_path) as logger:
        recorder = EpisodeRecorder(env, logger.recording)
        metrics = run_episode(recorder, load_policy("two_balls", env), seed=0)
    _, markers = column(logger.path, "plots/throws", "Scalars:scalars", "sim_time")
    assert min(metrics.throws_per_ball) >= 2
    assert len(markers) == metrics.throws and (markers >= 1.0).all()


# --- evaluate.py ---------------------------------------------------------------------------
@pytest.mark.slow
def test_evaluate_records_the_episode_it_runs(tmp_path):
    result = run_evaluate("policy=expert", "duration=12", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 0, result.stderr
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    path = tmp_path / "episode.rrd"
    verify(path)
    _, heights = column(path, "plots/ball_height", "Scalars:scalars", "sim_time")
    assert count_throws(heights, np.ones_like(heights, dtype=bool), 1.0) == metrics["throws"]
    summary = column(path, "summary", "TextDocument:text")[1][0]
    assert f"| throws | {metrics['throws']} |" in summary  # a table, not a point in a plot
    assert RrdReader(path).blueprints(), "no default layout was sent"


def plot_recording(path: Path, out: Path, seconds: float) -> subprocess.CompletedProcess:
    """``python scripts/plot_recording.py PATH --out OUT --seconds SECONDS``, checked to succeed."""
    script = Path(__file__).resolve().parents[1] / "scripts" / "plot_recording.py"
    result = subprocess.run(
        [sys.executable, str(script), str(path), "--out", str(out), "--seconds", str(seconds)],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    return result


@pytest.mark.slow
def test_plot_recording_draws_the_ball_height_from_a_file(tmp_path):
    path, metrics, _ = record_expert(tmp_path, duration=8.0)
    out = tmp_path / "plot.png"
    result = plot_recording(path, out, seconds=8)
    assert f"1 ball(s), 401 heights each, {metrics.throws} throws" in result.stdout
    image = iio.imread(out)
    assert image.shape == (300, 900, 3)
    red = (image == [230, 60, 60]).all(axis=-1)  # the height line is drawn
    assert red.sum() > 500


@pytest.mark.slow
def test_a_two_ball_recording_plots_each_balls_height_in_its_colour(tmp_path):
    path, _, _ = record_expert(tmp_path, duration=3.0, balls=2)
    first = column(path, "plots/ball_height", "Scalars:scalars", "sim_time")
    second = column(path, "plots/ball_1_height", "Scalars:scalars", "sim_time")
    np.testing.assert_array_equal(first[0], second[0])
    assert (second[1][:10] > first[1][:10] + 1.5).all()  # the second starts 2 m higher
    out = tmp_path / "plot.png"
    result = plot_recording(path, out, seconds=3)
    assert "2 ball(s), 151 heights each" in result.stdout
    image = iio.imread(out)
    blue = (image == [26, 76, 230]).all(axis=-1)  # the second ball's colour (scene.py)
    assert blue.sum() > 200
