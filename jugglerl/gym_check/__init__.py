"""The trainers' learners on a standard Gymnasium task: the check that tells a bug in a learner
from a hard task (``scripts/benchmarks/gym_check.py``, docs/results/gym_check.md).

- ``task_env``: N copies of a Gymnasium env as one TorchRL env, under the juggling env's
  conventions, and the deterministic evaluation of an actor on it;
- ``run``: the loop both checks share (collect, learn, the returns of the finished episodes);
- ``ppo``: ``algo=ppo``'s learner (``jugglerl.onpolicy``);
- ``offpolicy``: the off-policy trainer's RL losses (``td3``, ``ddpg``:
  ``jugglerl.offpolicy.losses``).
"""
