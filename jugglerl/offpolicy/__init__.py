"""Closed-loop off-policy learning (the paper's DDPG and its future work; TD3, behaviour cloning).

- ``env_stack.make_env``: the env batched in one process under TorchRL transforms, raw
  observation kept beside the networks' ``state``;
- ``timestamp.TimestampFeatures``: elapsed time and cycle phase appended to the state;
- ``actors`` (plug-ins: ``mlp``, ``lstm``, ``residual``) and ``critic``;
- ``exploration`` (plug-ins: ``ou``, ``gaussian`` centred on a command or a teacher);
- ``teacher.TeacherModule``: any policy acting in the loop, labelling every transition;
- ``losses`` (plug-ins: ``ddpg``, ``td3``, ``bc``) with the shared optimisers and soft targets;
- ``buffer.ReplayBuffer``: uniform transitions, or sub-trajectories for a recurrent actor;
- ``evaluation.Evaluations``: periodic evaluation and the deployed actor;
- ``training.OffPolicyTraining``: the loop behind ``scripts/train.py`` (``algo=ddpg|td3|bc``).
"""
