"""A deployed actor as one TorchScript file that runs with plain ``torch``.

``trace`` records ``DeployedActor``'s forward pass (state encoder, network, memory) as a
TorchScript module: ``(observation [N, 18] float64, time [N] float64, memory [N, M] float64) ->
(action [N, 3] float32, memory)``, with ``M = int(module.memory_size)`` and zeros starting an
episode. ``torch.jit.load`` runs it without JuggleRL, TorchRL or TensorDict installed; its
actions are those of ``ActorPolicy`` bit for bit (``docs/deploy.md``).

TorchScript, though torch marks ``torch.jit`` deprecated in favour of ``torch.export``: the
``torch.export`` program of the same module acts identically but, loaded back, took about 19 ms a
step for ``lstm_centred`` against 0.2 ms for the TorchScript file (one env, this project's
2-core machine). The tracer's notes on ``nn.LSTM``'s shape checks (constants of the trace, true
for any batch) and the deprecation notes are silenced.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import torch

from jugglerl.policies.actor import DeployedActor
from jugglerl.runs.files import write_atomically


def trace(deployed: DeployedActor) -> torch.jit.ScriptModule:
    """``deployed`` as a TorchScript module, for any batch size."""
    rows = 2  # a batch dim that is not 1, so that no size-1 broadcast is recorded
    example = (
        torch.zeros(rows, deployed.encoder.observation_size, dtype=torch.float64),
        torch.zeros(rows, dtype=torch.float64),
        torch.zeros(rows, int(deployed.memory_size), dtype=torch.float64),
    )
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore", torch.jit.TracerWarning)
        warnings.simplefilter("ignore", DeprecationWarning)
        return torch.jit.trace(deployed, example)


def export(deployed: DeployedActor, path: Path) -> Path:
    """Write ``trace(deployed)`` to ``path`` (atomically: ``RunFileError`` if it cannot)."""
    module = trace(deployed)
    path.parent.mkdir(parents=True, exist_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        write_atomically(path, lambda file: torch.jit.save(module, file))
    return path
