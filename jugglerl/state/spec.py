"""``resized``: the spec of the networks' ``state`` once a transform has changed its size."""

from __future__ import annotations

from torchrl.data import TensorSpec, Unbounded


def resized(spec: TensorSpec, size: int) -> Unbounded:
    """An unbounded spec of ``spec``'s batch shape, dtype and device with ``size`` values."""
    return Unbounded(shape=(*spec.shape[:-1], size), dtype=spec.dtype, device=spec.device)
