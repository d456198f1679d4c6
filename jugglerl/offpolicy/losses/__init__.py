"""Losses: what one update of the off-policy trainer does with a sampled batch.

Each module registers a class in ``LOSSES`` (chosen by ``algo.loss``) built as
``Loss(actor, state_size, action_spec, cfg)``; calling it with a batch updates the networks and
returns its losses as floats. ``Update`` holds what they share: the actor's (and critics')
Adam optimisers, gradient clipping, the soft target update and the checkpoint state. The losses
are TorchRL's (``DDPGLoss``, ``TD3Loss``) or ours (behaviour cloning, ``bc``), and every RL loss
can add a weighted behaviour-cloning term on a teacher's actions (``algo.bc_weight``, TD3+BC
style). Adding one: a module here and a ``configs/algo/NAME.yaml`` (``trainer: offpolicy``,
``loss: NAME``, ``defaults: [/offpolicy]``).
"""

from jugglerl_envs.registry import Registry

LOSSES = Registry("algo.loss", __name__)
