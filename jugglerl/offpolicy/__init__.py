"""Closed-loop off-policy learning (the paper's DDPG and its future work; TD3, behaviour cloning).

The env stack (``jugglerl.batch.env_stack``), the actors and critic (``jugglerl.networks``) and
the state's transforms (``jugglerl.state``) are shared with the other trainers; here:

- ``exploration`` (plug-ins: ``ou``, ``gaussian`` centred on the expert command);
- ``teacher.TeacherModule``: any policy run in the loop, labelling every transition;
- ``who_acts.WhoActs``: a stage's ``acts`` (the teacher or the student) and ``noise``;
- ``losses`` (plug-ins: ``ddpg``, ``td3``, ``bc``) with the shared optimisers and soft targets;
- ``buffer.ReplayBuffer``: uniform transitions, or sub-trajectories for a recurrent actor;
- ``stages``: the schedule of a staged pipeline (behaviour cloning, DAgger, residual RL);
- ``training.OffPolicyTraining``: the loop behind ``scripts/train.py`` (``algo=ddpg|td3|bc``,
  ``algo=apprentice``).
"""
