"""What the tests of every search space check alike."""

import torch

from jugglerl.dps.distribution import SearchDistribution


def assert_wide_samples_are_valid_policies(space, env, policy_type) -> torch.Tensor:
    """2000 samples of thirty times the space's stds, all within its constraints, every entry
    still varying, and the first one a ``policy_type`` that acts in ``env``; returns them."""
    wide = SearchDistribution.diagonal(space.start, space.stds * 30)
    samples = wide.sample(2000, torch.Generator().manual_seed(0), space)
    assert all(space.violations(theta) == [] for theta in samples)
    assert samples.std(0).min() > 0
    policy = space.policy(samples[0], env)
    assert isinstance(policy, policy_type)
    observation, info = env.reset(seed=0)
    policy.reset()
    assert policy.act(observation, info["time"]).shape == (3,)
    return samples
