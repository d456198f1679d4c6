"""The simulation behind ``scripts/studies/earth_throw.py``: one throw from rest at real gravity
(``env=earth``), decoded from a flat vector, simulated, scored and searched by CMA-ES.

The vector is a start pose (shoulder lift, elbow; wrist_1 set so the cup is upright there, plus a
tilt), then ``KNOTS`` setpoint knots (duration, lift, elbow) that the env's rate limit turns into
ramps. The score is the ball's apex after it leaves the cup, less 10 per metre the cup's throat
rises above ``max_cup`` and ``landing_weight`` per metre the ball comes down from the start cup.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources

import numpy as np
from cmaes import CMA
from omegaconf import OmegaConf

from jugglerl_envs import JuggleEnv
from jugglerl_envs.actions import ctrl_to_action

EARTH = OmegaConf.load(str(resources.files("jugglerl.configs").joinpath("env/earth.yaml")))
GRAVITY, SPEED_LIMIT = EARTH.gravity, EARTH.joint_speed_limit  # m/s², rad/s; the rest as paper
UPRIGHT = (-1.5708, 2.0, -2.0)  # lift, elbow, wrist_1: the cup upright (policies/expert.yaml)
KNOTS = 3
SETTLE = 0.6  # s at the start pose before the throw
FLIGHT = 1.2  # s simulated after the last knot ends
MAX_KNOT = 0.6  # s, the longest a knot lasts
LIFT, ELBOW = (-np.pi, 0.0), (0.0, np.pi)  # the servos' control ranges (rad)


@dataclass
class Throw:
    apex: float  # m, the ball's highest point after it left the cup (0: it never left)
    max_cup: float  # m, the cup's throat at its highest
    peak_speed: tuple[float, ...]  # rad/s, per actuated joint
    landing_offset: float  # m, horizontal distance from the start cup when it falls back past it
    throws: int  # counted by the env (crossings of 1 m in free flight)


def decode(x: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Start pose (lift, elbow), tilt (rad) and knots ``[duration s, lift, elbow] x KNOTS`` from a
    flat vector, inside the servos' ranges."""
    start = np.array([np.clip(x[0], *LIFT), np.clip(x[1], *ELBOW)])
    tilt = float(np.clip(x[2], -0.6, 0.6))
    knots = x[3:].reshape(KNOTS, 3).copy()
    knots[:, 0] = np.minimum(np.abs(knots[:, 0]) + 0.02, MAX_KNOT)
    knots[:, 1] = np.clip(knots[:, 1], *LIFT)
    knots[:, 2] = np.clip(knots[:, 2], *ELBOW)
    return start, tilt, knots


def earth_env() -> JuggleEnv:
    """The earth env, long enough for any throw; ``simulate`` sets its start pose per throw."""
    return JuggleEnv(
        gravity=GRAVITY,
        joint_speed_limit=SPEED_LIMIT,
        drop_height=0.06,
        duration=SETTLE + KNOTS * MAX_KNOT + FLIGHT,
    )


def simulate(x: np.ndarray, env: JuggleEnv | None = None) -> Throw | None:
    """The throw of ``x`` in the earth env; ``None`` when its start cannot hold the ball."""
    start, tilt, knots = decode(x)
    wrist_1 = UPRIGHT[2] - (start[0] - UPRIGHT[0]) - (start[1] - UPRIGHT[1]) + tilt
    env = env or earth_env()
    env.home = np.array([0.0, *start])  # the next reset starts here (the env kwargs)
    env.wrist_angles = np.array([wrist_1, 1.5708, 0.0])
    observation, _ = env.reset(seed=0)
    cup_start = observation[12:15].copy()
    if cup_start[2] < 0.25:
        return None
    ends = SETTLE + np.cumsum(knots[:, 0])
    apex, left, landing = 0.0, False, None
    done, info = False, {}
    while not done and env.data.time < ends[-1] + FLIGHT:
        time = env.data.time
        index = min(int(np.searchsorted(ends, time, side="right")), KNOTS - 1)
        pose = start if time < SETTLE else knots[index, 1:]
        observation, _, terminated, truncated, info = env.step(ctrl_to_action(np.r_[0.0, pose]))
        done = terminated or truncated
        ball, cup = observation[6:9], observation[12:15]
        if time < SETTLE and time + env.dt >= SETTLE and np.linalg.norm(ball[:2] - cup[:2]) > 0.08:
            return None  # the ball did not settle in the cup
        left = left or ball[2] - cup[2] > 0.15
        if left:
            apex = max(apex, ball[2])
            if landing is None and ball[2] < min(apex - 0.05, cup_start[2] + 0.1):
                landing = float(np.linalg.norm(ball[:2] - cup_start[:2]))
    return Throw(
        apex=apex if left else 0.0,
        max_cup=float(info["max_cup_height"]),
        peak_speed=tuple(float(v) for v in info["peak_joint_speed"]),
        landing_offset=np.inf if landing is None else landing,
        throws=int(info["throws"]),
    )


def score(throw: Throw | None, max_cup: float, landing_weight: float = 0.0) -> float:
    if throw is None:
        return -1.0
    value = throw.apex - 10.0 * max(0.0, throw.max_cup - max_cup)
    if landing_weight > 0:  # a ball that never comes back down past the cup is 1 m off
        value -= landing_weight * min(throw.landing_offset, 1.0)
    return value


def search(restarts: int, generations: int, seed: int, max_cup: float, landing_weight: float):
    """CMA-ES restarts from random start poses; the best vector and its throw."""
    rng = np.random.default_rng(seed)
    env = earth_env()
    best_x, best_score = None, -np.inf
    for restart in range(restarts):
        lift, elbow = rng.uniform(-1.8, -0.6), rng.uniform(1.0, 2.4)
        knots = np.tile([0.15, lift - 0.6, elbow - 0.6], KNOTS)
        es = CMA(
            mean=np.r_[lift, elbow, 0.0, knots], sigma=0.3, seed=seed + restart, population_size=16
        )
        for _ in range(generations):
            told = []
            for _ in range(es.population_size):
                x = es.ask()
                value = score(simulate(x, env), max_cup, landing_weight)
                told.append((x, -value))
                if value > best_score:
                    best_x, best_score = x, value
            es.tell(told)
        print(f"restart {restart + 1}/{restarts}: best score so far {best_score:.3f}", flush=True)
    return best_x, simulate(best_x, env)
