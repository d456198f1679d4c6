"""Search spaces of Direct Policy Search: what θ is, how it is constrained and rolled out.

The search loop (``jugglerl.dps.training.SearchTraining``) is given a space, chosen by
``algo.space`` from ``SPACES``; a space is a class built from the run config with

- ``start``, ``stds``: the first search distribution's mean and per-entry stds (float64);
- ``project(params)``, ``violations(params)``: the constraints (samples are projected);
- ``decode(params)``: what the roll-outs evaluate for one θ;
- ``rollouts(reset_noise=None)``: a context manager whose ``evaluate(candidates, seeds)`` gives
  ``RolloutResults`` (``reset_noise=None``: the search's own start noise);
- ``search_env()``: the env of the roll-outs, for replaying and recording a θ;
- ``policy(params, env)``: θ as a ``Policy``; ``save(params, run_dir, name)`` writes it as a
  policy file and returns the file's name (what the checkpoint ``deploys``);
- ``describe(params)`` and ``record(distribution)``: what the metrics keep of the best θ and of
  the distribution each episode; ``headline(metrics)``: the run's one-line result.

Adding one: a module here registering its class, and a ``configs/algo/NAME.yaml`` with
``trainer: search`` and ``space: NAME``.
"""

from jugglerl_envs.registry import Registry

SPACES = Registry("algo.space", __name__)
