"""Closed-loop DDPG on the juggling env (the paper's second method, with its future work).

- ``env_stack.make_env``: the env batched in one process under TorchRL transforms;
- ``timestamp.TimestampFeatures``: elapsed time and cycle phase appended to the state;
- ``actors``: the MLP and LSTM actors and the MLP critic;
- ``exploration``: Ornstein-Uhlenbeck noise and ``ExpertGaussianNoise`` (centred on the expert);
- ``update.DDPGUpdate``: loss, optimisers and soft target networks;
- ``buffer.ReplayBuffer``: uniform transitions, or sub-trajectories for the LSTM;
- ``policy.ActorPolicy``: a trained actor on plain Gymnasium envs (evaluation, recording);
- ``training.DDPGTraining``: the loop behind ``scripts/train.py`` (``algo=ddpg``, the default).
"""
