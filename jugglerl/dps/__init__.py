"""Direct Policy Search over open-loop via-point commands (the paper's first method).

- ``params``: the flat θ layout of a command and the constraints samples are projected onto;
- ``distribution.SearchDistribution``: the Gaussian N(θ̃, Σ) the search samples from;
- ``updates``: greedy, reward-weighted, elite and episodic-REPS refits of that distribution;
- ``rollouts.CommandRollouts``: batches of commands evaluated in C at raw physics speed, throws
  counted exactly as the env counts them;
- ``collector.DPSCollector``: the TorchRL collector that yields a batch of scored samples per
  iteration;
- ``training.DPSTraining``: the loop behind ``scripts/train.py algo=dps`` (best command,
  checkpoints, logging).
"""
