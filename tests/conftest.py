"""Shared fixtures for the tests."""

import numpy as np
import pytest

from jugglerl_envs import JuggleEnv


@pytest.fixture
def hold():
    """``hold(env)``: the normalised action that keeps the arm at its home pose."""

    def action(env: JuggleEnv) -> np.ndarray:
        return env.ctrl_to_action(env.home)

    return action
