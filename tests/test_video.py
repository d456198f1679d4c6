"""Videos of episodes: ``evaluate.py video=true`` and ``VideoRecorder``."""

import json

import av
import mujoco
import numpy as np
import pytest
from cli import run_script
from PIL import Image

from jugglerl.policies.episodes import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl.recording.video import VideoError, VideoOptionError, VideoRecorder
from jugglerl_envs import JuggleEnv


def renderer_or_skip():
    try:
        mujoco.Renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 16, 16).close()
    except Exception as error:  # CI installs EGL (.ci/run); elsewhere it may be missing
        pytest.skip(f"no OpenGL for MuJoCo's offscreen renderer: {error}")


def decoded_frames(path) -> list[np.ndarray]:
    with av.open(str(path)) as container:
        return [frame.to_ndarray(format="rgb24") for frame in container.decode(video=0)]


@pytest.mark.slow
def test_evaluate_writes_a_playable_real_time_mp4_and_the_same_episode(tmp_path):
    renderer_or_skip()
    plain, filmed = tmp_path / "plain", tmp_path / "filmed"
    common = ("policy=closed_loop", "duration=3", "render.fps=20")
    assert run_script("evaluate.py", *common, f"hydra.run.dir={plain}").returncode == 0
    result = run_script("evaluate.py", *common, "video=true", f"hydra.run.dir={filmed}")
    assert result.returncode == 0, result.stderr
    assert "episode.mp4 (61 frames)" in result.stdout

    frames = decoded_frames(filmed / "episode.mp4")
    assert len(frames) == 61  # t = 0, 0.05, ..., 3.0 s: real time at 20 frames per second
    assert frames[0].shape == (480, 640, 3)
    assert all(frame.std() > 10 for frame in frames)  # the scene, not a blank buffer
    assert np.abs(frames[-1].astype(int) - frames[0]).mean() > 1  # the arm moved
    with av.open(str(filmed / "episode.mp4")) as container:
        assert container.streams.video[0].codec_context.name == "h264"
        assert float(container.streams.video[0].average_rate) == 20

    metrics = [json.loads((run / "metrics.json").read_text()) for run in (plain, filmed)]
    assert metrics[0] == metrics[1]  # filming does not change the episode


@pytest.mark.slow
def test_a_webp_loops_and_has_a_frame_per_period(tmp_path):
    renderer_or_skip()
    env = JuggleEnv(duration=1.0)
    recorder = VideoRecorder(env, tmp_path / "clip.webp", fps=10, width=160, height=120)
    run_episode(recorder, load_policy("closed_loop", env), seed=0)
    recorder.close()
    with Image.open(tmp_path / "clip.webp") as image:
        assert image.n_frames == recorder.frames == 11
        assert image.info["loop"] == 0 and image.size == (160, 120)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"path": "clip.avi"}, "file=clip.avi: the suffix must be one of .mp4, .webp, .gif"),
        ({"width": 641}, "width=641, height=480: the size must be even and positive"),
        ({"fps": 60}, "fps=60 must be in (0, 50]"),
        ({"camera": "top"}, "camera=top is not in the scene; cameras: "),
    ],
)
def test_bad_video_options_are_one_line(tmp_path, options, message):
    arguments = {"path": tmp_path / "clip.mp4", **options}
    with pytest.raises(VideoOptionError, match=message.replace("(", r"\(").replace(")", r"\)")):
        VideoRecorder(JuggleEnv(), **arguments)


def test_no_opengl_is_one_line_naming_the_backend_and_the_packages(tmp_path, monkeypatch):
    def no_gl(*args, **kwargs):
        raise RuntimeError("The MUJOCO_GL environment variable is set to egl\nbut EGL failed")

    monkeypatch.setattr(mujoco, "Renderer", no_gl)
    monkeypatch.setenv("MUJOCO_GL", "egl")
    with pytest.raises(VideoError) as error:
        VideoRecorder(JuggleEnv(), tmp_path / "clip.mp4")
    assert "\n" not in str(error.value)
    assert str(error.value).startswith("video needs OpenGL for MuJoCo's offscreen renderer")
    assert "MUJOCO_GL=egl" in str(error.value) and "apt-get install libegl1" in str(error.value)
    assert not (tmp_path / "clip.mp4").exists()


def test_an_unknown_mujoco_gl_is_one_line_before_mujoco_is_imported(tmp_path):
    """MuJoCo's import raises on an unknown backend; the env package says so first, in a fresh
    interpreter (the tests' script runner has MuJoCo imported already)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    result = subprocess.run(
        [sys.executable, str(root / "scripts" / "evaluate.py"), f"hydra.run.dir={tmp_path}"],
        env={**os.environ, "MUJOCO_GL": "foo"},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr.strip() == (
        "error: MUJOCO_GL=foo is not a MuJoCo rendering backend here; use one of egl, osmesa,"
        " glfw, glx, or unset it"
    )


def test_a_backend_whose_library_is_missing_is_one_line(tmp_path):
    """``MUJOCO_GL=osmesa`` without OSMesa: MuJoCo's import fails inside PyOpenGL."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    # as in a user's shell: the tests' own MuJoCo import has set PyOpenGL's platform to EGL
    environment = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"}
    environment["MUJOCO_GL"] = "osmesa"
    probe = subprocess.run([sys.executable, "-c", "import mujoco"], env=environment)
    if probe.returncode == 0:
        pytest.skip("OSMesa is installed here: MuJoCo imports with MUJOCO_GL=osmesa")
    root = Path(__file__).resolve().parents[1]
    result = subprocess.run(
        [sys.executable, str(root / "scripts" / "evaluate.py"), f"hydra.run.dir={tmp_path}"],
        env=environment,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("error: MUJOCO_GL=osmesa: MuJoCo could not load this OpenGL backend (")
    assert line.endswith("choose another of egl, osmesa, glfw, glx, or unset it")
