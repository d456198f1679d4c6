"""Many juggling episodes at once, on ``jugglerl_envs.JuggleBatch``.

- ``torchrl_env.JuggleBatchEnv``: the batch as a TorchRL env (``batch_size=[N]``), for collectors
  and the trainers' transform stacks;
- ``collector.BatchCollector``: batches of steps from the env stack, the envs' running episodes
  carried from batch to batch and through checkpoints (both trainers collect with it);
- ``episodes.run_episodes``: a policy's episodes from many starts and under many conditions in
  one batch, summarised as ``EpisodeMetrics`` (evaluations, the robustness benchmark).
"""
