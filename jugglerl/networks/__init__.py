"""The networks: actors (plug-ins in ``actors/``), the critic, and the modules they are built of.

Training (``jugglerl.offpolicy``) and deployment (``jugglerl.policies.actor.ActorPolicy``) both
build their networks from here, so a trained actor runs outside the trainer unchanged.

- ``actors``: deterministic networks from the ``state`` to an ``action`` (``mlp``, ``lstm``,
  ``residual``; any of them with a bounded ``correction`` on top);
- ``critic``: Q(state, action);
- ``reference.CommandReference``: a via-point command's action at episode times, in torch;
- ``modules.TensorModule``: the fast ``TensorDictModule`` they are made of.
"""
