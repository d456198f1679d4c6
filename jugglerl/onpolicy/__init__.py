"""On-policy learning: PPO on the batched juggling env (``algo=ppo``).

- ``agent``: the Gaussian policy around an actor's action (any feed-forward actor of
  ``jugglerl.networks.actors``; the ``residual`` one plays a command, so that the untrained
  policy's mean is the command itself) and the critic ``V(state)``;
- ``variants``: the perturbations each env of the training batch runs under;
- ``training.PPOTraining``: the loop behind ``scripts/train.py algo=ppo``: collect, advantages
  (GAE), clipped PPO updates (TorchRL's ``ClipPPOLoss``), log, evaluate, checkpoint.
"""
