"""Exported networks (``scripts/export_policy.py``): one TorchScript file that acts as
``ActorPolicy`` does, bit for bit, run by the plain-``torch`` lines of ``docs/deploy.md``."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
import torch
from cli import ROOT, run_script

from jugglerl.policies.actor import ActorPolicy
from jugglerl.policies.actor_file import read_actor_weights
from jugglerl.policies.export import export, trace
from jugglerl_envs import JuggleEnv

#: What the snippet may not import: the file must run with plain torch.
PROJECT_MODULES = ("jugglerl", "torchrl", "tensordict")


def deploy_snippet() -> str:
    """The Python block of docs/deploy.md that runs an exported file."""
    text = (ROOT / "docs" / "deploy.md").read_text()
    return re.search(r"```python\n(.*?)```", text, re.S).group(1)


def episode(policy: ActorPolicy, duration: float) -> tuple[np.ndarray, ...]:
    """Observations, times and actions of ``policy`` from the standard start."""
    env = JuggleEnv(duration=duration)
    observation, info = env.reset(seed=0)
    policy.reset()
    observations, times, actions = [], [], []
    done = False
    while not done:
        action = policy.act(observation, info["time"])
        observations.append(observation)
        times.append(info["time"])
        actions.append(action)
        observation, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    return np.array(observations), np.array(times), np.array(actions)


@pytest.mark.parametrize("name", ["lstm_centred", "ppo_juggler"])
@pytest.mark.slow
def test_the_docs_lines_run_the_exported_file_as_actor_policy_acts_over_30_s(tmp_path, name):
    policy = ActorPolicy.from_state(read_actor_weights(name))
    observations, times, actions = episode(policy, duration=30.0)
    assert len(times) == 1500  # the ball stayed up: a whole 30-s episode
    export(policy.deployed, tmp_path / "lstm_centred.pt")  # the file name the snippet loads
    np.save(tmp_path / "observations.npy", observations)
    np.save(tmp_path / "times.npy", times)
    blocked = "".join(f"sys.modules[{module!r}] = None\n" for module in PROJECT_MODULES)
    program = (
        f"import sys\n{blocked}{deploy_snippet()}\n"
        "import numpy as np\n"
        "observations, times = np.load('observations.npy'), np.load('times.npy')\n"
        "np.save('actions.npy', np.stack([act(o, t) for o, t in zip(observations, times)]))\n"
    )
    subprocess.run([sys.executable, "-c", program], cwd=tmp_path, check=True, timeout=120)
    np.testing.assert_array_equal(np.load(tmp_path / "actions.npy"), actions)


def test_the_exported_file_acts_on_a_batch_as_actor_policy_does():
    policy = ActorPolicy.from_state(read_actor_weights("lstm_centred"))
    observations, times, _ = episode(policy, duration=4.0)
    exported = trace(policy.deployed)
    rows = np.array([0, 50, 51, 120, 190])  # five envs, each at its own moment
    memory = torch.zeros(len(rows), int(exported.memory_size), dtype=torch.float64)
    policy.reset()
    for step in range(5):
        observation, time = observations[rows + step], times[rows + step]
        expected = policy.act(observation, time)
        action, memory = exported(torch.as_tensor(observation), torch.as_tensor(time), memory)
        np.testing.assert_array_equal(action.detach().numpy(), expected)


def test_export_policy_writes_the_file_it_names(tmp_path):
    result = run_script("export_policy.py", "policy=ppo_juggler", f"file={tmp_path}/ppo.pt")
    assert result.returncode == 0, result.stderr
    assert str(tmp_path / "ppo.pt") in result.stdout
    exported = torch.jit.load(str(tmp_path / "ppo.pt"))
    assert int(exported.memory_size) == 3  # started, the ball clock's lock time and armed flag


@pytest.mark.parametrize(
    "policy, message",
    [
        ("", "error: policy is empty: give a shipped policy"),
        ("nowhere", "error: policy=nowhere: no policy file at"),
        ("expert", "expert.yaml: not a kind: actor file"),
    ],
)
def test_export_policy_refuses_what_is_no_network_in_one_line(tmp_path, policy, message):
    result = run_script("export_policy.py", f"policy={policy}", f"hydra.run.dir={tmp_path}")
    assert result.returncode == 1
    assert message in result.stderr and "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
