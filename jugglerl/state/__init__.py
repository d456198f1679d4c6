"""The networks' input ``state``: the observation's parts, normalised, with time features.

Built as TorchRL transforms (``transforms.state_transforms``) that the training env stack
(``jugglerl.batch.env_stack``) and a deployed actor (``jugglerl.policies.actor``) share:

- ``observation_parts.ObservationParts``: which parts of the env's observation the networks see;
- ``timestamp.TimestampFeatures``: elapsed time and the phase of a cycle;
- ``ball_clock.BallClock``: the time since the ball last fell into the cup's reach;
- ``spec.resized``: the spec of ``state`` once a transform changes its size.
"""
