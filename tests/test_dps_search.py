"""θ layout, constraints, the search distribution and the four update rules."""

import math

import pytest
import torch
from omegaconf import OmegaConf

from jugglerl.commands import load_command
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.params import (
    ViaPointConstraints,
    command_to_params,
    component_stds,
    params_to_command,
)
from jugglerl.dps.updates import UPDATES, make_update
from jugglerl.dps.updates.cma_es import CMAES
from jugglerl.dps.updates.elite import Elite
from jugglerl.dps.updates.ereps import EpisodicREPS, ereps_weights
from jugglerl.dps.updates.greedy import Greedy
from jugglerl.dps.updates.weighted import RewardWeighted
from jugglerl_envs import JuggleEnv

CONSTRAINTS = ViaPointConstraints(
    min_cycle=1.0, max_cycle=5.0, min_gap=0.1, lift_range=(-3.1416, 0.0), elbow_range=(0.0, 3.1416)
)


def test_layout_round_trips_a_command():
    expert = load_command("expert")
    params = command_to_params(expert)
    assert params.tolist() == [3.0, 0.0, -1.5708, 2.15, 1.5, -1.5708, 1.5, 2.0, -1.5708, 2.15]
    assert params_to_command(params, expert.pan) == expert
    assert CONSTRAINTS.violations(params) == []


def test_constraints_come_from_the_servo_ranges():
    constraints = ViaPointConstraints.from_model(JuggleEnv().model, 1.0, 5.0, 0.1)
    assert constraints.lift_range == pytest.approx((-3.1416, 0.0))
    assert constraints.elbow_range == pytest.approx((0.0, 3.1416))


@pytest.mark.parametrize("seed", range(20))
def test_every_projected_sample_is_a_valid_command(seed):
    generator = torch.Generator().manual_seed(seed)
    points = int(torch.randint(1, 6, (1,), generator=generator))
    # wild samples: cycles beyond both bounds, times out of order and outside the cycle,
    # angles far outside the servo ranges
    raw = torch.randn(500, 1 + 3 * points, generator=generator, dtype=torch.float64) * 4
    raw[:, 0] += 3.0
    params = CONSTRAINTS.project(raw)
    for theta in params:
        assert CONSTRAINTS.violations(theta) == []
        params_to_command(theta)  # ViaPointCommand validates the times against the cycle too


def test_projection_keeps_each_via_point_with_its_angles():
    raw = torch.tensor([2.0, 1.5, -1.0, 1.0, 0.2, -2.0, 2.0], dtype=torch.float64)
    projected = CONSTRAINTS.project(raw)
    assert projected.tolist() == [2.0, 0.2, -2.0, 2.0, 1.5, -1.0, 1.0]
    assert torch.equal(CONSTRAINTS.project(projected), projected)  # valid θ are left alone


def test_too_many_via_points_for_the_shortest_cycle_is_an_error():
    with pytest.raises(ValueError, match="do not fit"):
        CONSTRAINTS.project(torch.zeros(1 + 3 * 11, dtype=torch.float64))


def test_component_stds_follow_the_layout():
    stds = component_stds(2, {"cycle": 0.05, "time": 0.02, "lift": 0.01, "elbow": 0.03})
    assert stds.tolist() == [0.05, 0.02, 0.01, 0.03, 0.02, 0.01, 0.03]
    with pytest.raises(ValueError, match="missing stds for \\['elbow'\\]"):
        component_stds(2, {"cycle": 0.05, "time": 0.02, "lift": 0.01})


def test_samples_have_the_distributions_mean_and_stds():
    expert = command_to_params(load_command("expert"))
    stds = component_stds(3, {"cycle": 0.05, "time": 0.02, "lift": 0.02, "elbow": 0.01})
    distribution = SearchDistribution.diagonal(expert, stds)
    samples = distribution.sample(20000, torch.Generator().manual_seed(0), CONSTRAINTS)
    free = [0, 2, 3, 4, 5, 6, 7, 8, 9]  # t_1 = 0 sits on its bound: clamped samples skew it
    assert torch.allclose(samples.mean(0)[free], expert[free], atol=4 * 0.05 / 20000**0.5)
    assert torch.allclose(samples.std(0)[free], stds[free], rtol=0.03)
    assert samples[:, 1].min() == 0.0


def test_sampling_is_reproducible_from_the_generator_seed():
    distribution = SearchDistribution.diagonal(torch.zeros(4) + 2.0, torch.ones(4) * 0.1)
    first = distribution.sample(5, torch.Generator().manual_seed(3), CONSTRAINTS)
    again = distribution.sample(5, torch.Generator().manual_seed(3), CONSTRAINTS)
    other = distribution.sample(5, torch.Generator().manual_seed(4), CONSTRAINTS)
    assert torch.equal(first, again) and not torch.equal(first, other)


def test_a_singular_covariance_samples_on_its_subspace():
    cov = torch.zeros(4, 4, dtype=torch.float64)
    cov[0, 0] = 0.01  # only the cycle varies
    distribution = SearchDistribution(torch.tensor([2.0, 0.5, -1.0, 1.0]), cov)
    samples = distribution.sample(100, torch.Generator().manual_seed(0), CONSTRAINTS)
    assert samples[:, 0].std() > 0.05
    assert torch.all(samples[:, 1:] == torch.tensor([0.5, -1.0, 1.0], dtype=torch.float64))


# --- update rules on a toy objective with a known optimum ------------------------------------
OPTIMUM = torch.tensor([1.0, -2.0, 0.5], dtype=torch.float64)


def toy_returns(params: torch.Tensor) -> torch.Tensor:
    """A positive bump whose maximum is at ``OPTIMUM``."""
    return 100 * torch.exp(-((params - OPTIMUM) ** 2).sum(-1) / 8)


class Unconstrained:
    @staticmethod
    def project(params):
        return params


def optimise(
    rule,
    iterations: int = 30,
    samples: int = 25,
    generator: torch.Generator | None = None,
    distribution: SearchDistribution | None = None,
) -> SearchDistribution:
    if distribution is None:
        distribution = SearchDistribution.diagonal(torch.zeros(3), torch.full((3,), 0.5))
    generator = generator or torch.Generator().manual_seed(0)
    for _ in range(iterations):
        params = distribution.sample(samples, generator, Unconstrained)
        distribution = rule(distribution, params, toy_returns(params))
    return distribution


@pytest.mark.parametrize(
    "rule, tolerance",
    [
        (lambda: Greedy(), 0.3),
        (lambda: RewardWeighted(), 1.0),  # weights ∝ R move slowly on a wide bump
        (lambda: Elite(5, torch.full((3,), 0.05)), 0.1),
        (lambda: EpisodicREPS(2.0, torch.full((3,), 0.05)), 0.1),
        (lambda: CMAES(25), 0.1),
    ],
    ids=["greedy", "weighted", "elite", "ereps", "cmaes"],
)
def test_each_update_moves_toward_the_optimum(rule, tolerance):
    start = float(torch.linalg.norm(OPTIMUM))
    final = optimise(rule())
    distance = float(torch.linalg.norm(final.mean - OPTIMUM))
    assert distance < tolerance < start


def test_cmaes_resumed_from_its_state_continues_to_the_same_samples(tmp_path):
    straight_generator = torch.Generator().manual_seed(3)
    straight = optimise(CMAES(25), iterations=10, generator=straight_generator)
    split_generator = torch.Generator().manual_seed(3)
    first = CMAES(25)
    half = optimise(first, iterations=5, generator=split_generator)
    torch.save({"update": first.state_dict(), "rng": split_generator.get_state()}, tmp_path / "c")
    saved = torch.load(tmp_path / "c", weights_only=False)
    resumed = CMAES(25)
    resumed.load_state_dict(saved["update"])
    generator = torch.Generator()
    generator.set_state(saved["rng"])
    again = optimise(resumed, iterations=5, generator=generator, distribution=half)
    assert torch.equal(again.mean, straight.mean) and torch.equal(again.cov, straight.cov)


def test_cmaes_grows_its_step_on_a_slope():
    """On a long slope the step size grows, so the search travels further than its first std."""
    rule = CMAES(10)
    distribution = SearchDistribution.diagonal(torch.zeros(2), torch.full((2,), 0.1))
    generator = torch.Generator().manual_seed(0)
    for _ in range(20):
        params = distribution.sample(10, generator, Unconstrained)
        distribution = rule(distribution, params, params[:, 0])  # more is better along x
    assert float(distribution.stds[0]) > 0.3 and float(distribution.mean[0]) > 3


def test_weighted_mean_is_the_reward_weighted_average():
    params = torch.tensor([[0.0, 0.0], [4.0, 2.0]], dtype=torch.float64)
    distribution = SearchDistribution.diagonal(torch.zeros(2), torch.ones(2))
    moved = RewardWeighted()(distribution, params, torch.tensor([1.0, 3.0]))
    assert moved.mean.tolist() == [3.0, 1.5] and torch.equal(moved.cov, distribution.cov)
    assert RewardWeighted()(distribution, params, torch.zeros(2)) is distribution


def test_greedy_keeps_the_best_ever_and_only_moves_on_improvement():
    rule = Greedy()
    distribution = SearchDistribution.diagonal(torch.zeros(2), torch.ones(2))
    params = torch.tensor([[1.0, 1.0], [2.0, 2.0]], dtype=torch.float64)
    first = rule(distribution, params, torch.tensor([5.0, 7.0]))
    assert first.mean.tolist() == [2.0, 2.0]
    assert rule(first, params * 10, torch.tensor([7.0, 6.0])) is first  # a tie is no improvement
    restored = Greedy()
    restored.load_state_dict(rule.state_dict())
    assert restored(first, params * 10, torch.tensor([7.0, 6.0])) is first


def test_elite_fits_the_top_samples_and_floors_the_std():
    params = torch.tensor([[0.0], [1.0], [3.0], [5.0]], dtype=torch.float64)
    fitted = Elite(2, torch.tensor([0.1]))(
        SearchDistribution.diagonal(torch.zeros(1), torch.ones(1)),
        params,
        torch.tensor([1.0, 2.0, 9.0, 8.0]),
    )
    assert fitted.mean.tolist() == [4.0] and fitted.stds.tolist() == pytest.approx([2**0.5])
    narrow = Elite(2, torch.tensor([0.1]))(fitted, params[:2] * 0 + 1, torch.tensor([1.0, 2.0]))
    assert narrow.stds.tolist() == pytest.approx([0.1])


@pytest.mark.parametrize("epsilon", [0.1, 0.5, 1.0, 2.0])
@pytest.mark.parametrize("seed", range(5))
def test_ereps_weights_meet_the_kl_bound(epsilon, seed):
    returns = torch.randn(25, generator=torch.Generator().manual_seed(seed)) * 10
    weights, eta = ereps_weights(returns, epsilon)
    kl = float((weights * torch.log(weights * len(weights))).sum())
    assert weights.sum() == pytest.approx(1.0)
    assert kl == pytest.approx(epsilon, abs=1e-6)  # the dual's optimum sits on the bound
    # the weights are exp(R / η): better samples weigh more, by the right factor
    best, worst = int(returns.argmax()), int(returns.argmin())
    ratio = math.exp(float(returns[best] - returns[worst]) / eta)
    assert float(weights[best] / weights[worst]) == pytest.approx(ratio, rel=1e-6)


def test_ereps_with_equal_returns_or_a_loose_bound():
    weights, _ = ereps_weights(torch.full((4,), 7.0), 1.0)
    assert weights.tolist() == [0.25] * 4
    # KL from uniform is at most log N: a bound above it makes the update greedy on the best
    weights, _ = ereps_weights(torch.tensor([0.0, 1.0, 2.0, 5.0]), 5.0)
    assert float(weights[3]) == pytest.approx(1.0)


def test_make_update_names_the_valid_choices():
    algo = OmegaConf.create(
        {"update": "ereps", "elite": 5, "rollouts": 10, "epsilon": 2.0, "min_std_scale": 0.5}
    )
    rule = make_update(algo, torch.ones(4))
    assert isinstance(rule, EpisodicREPS) and torch.equal(rule.min_stds, torch.full((4,), 0.5))
    assert UPDATES.names() == ("cmaes", "elite", "ereps", "greedy", "weighted")
    algo.update = "adam"
    with pytest.raises(ValueError, match="algo.update='adam' is not available; choose one of"):
        make_update(algo, torch.ones(4))
