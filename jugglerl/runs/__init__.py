"""What every run shares, whatever it trains: its files written so that a failed write loses
nothing (``files``), its checkpoints (``checkpoints``), the policy files it reads and ships
(``policy_files``), and Ctrl-C as a clean stop (``interrupts``)."""
