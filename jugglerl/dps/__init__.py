"""Direct Policy Search (the paper's first method), over pluggable search spaces.

- ``spaces``: what θ is (``via_points``: an open-loop command; ``feedback_gains``: the gains of
  the closed-loop ``FeedbackPolicy``), its constraints and its roll-outs;
- ``params``: the flat θ layout of a via-point command and its constraints;
- ``distribution.SearchDistribution``: the Gaussian N(θ̃, Σ) the search samples from;
- ``updates``: greedy, reward-weighted, elite and episodic-REPS refits of that distribution;
- ``rollouts.CommandRollouts``: batches of commands evaluated in C at raw physics speed, throws
  counted exactly as the env counts them;
- ``collector.DPSCollector``: the TorchRL collector that yields a batch of scored samples per
  iteration;
- ``training.SearchTraining``: the loop behind ``scripts/train.py algo=dps|feedback`` (best θ,
  checkpoints, logging).
"""
