"""Direct Policy Search over open-loop via-point commands (the paper's first method).

- ``rollouts.CommandRollouts``: batches of commands evaluated in C at raw physics speed, throws
  counted exactly as the env counts them.
"""
