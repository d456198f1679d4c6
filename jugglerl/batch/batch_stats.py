"""``BatchStats``: what the trainers log of each collected batch.

Per batch: the mean reward per step; the throws per minute of simulated time over the last
``window`` batches, seen long before any episode ends (one batch alone is bursty: the envs start
together and throw at the same moments); and the return, throws, catches and length of the
episodes that finished in it.
"""

from __future__ import annotations

from collections import deque

from tensordict import TensorDictBase

#: Batches the throw rate is measured over.
THROW_WINDOW = 10


class BatchStats:
    """Statistics of collected batches of an env stepping ``step_seconds`` per frame."""

    def __init__(self, step_seconds: float, window: int = THROW_WINDOW):
        self.step_seconds = step_seconds
        self.recent: deque[tuple[float, float]] = deque(maxlen=window)  # (throws, minutes)

    def state_dict(self) -> dict:
        """The throw-rate window, which a resumed run goes on measuring over."""
        return {"recent": list(self.recent)}

    def load_state_dict(self, state: dict) -> None:
        self.recent.clear()
        self.recent.extend(tuple(entry) for entry in state["recent"])

    def __call__(self, batch: TensorDictBase) -> dict[str, float]:
        thrown = float((batch["next", "throws"] - batch["throws"]).clamp(min=0).sum())
        self.recent.append((thrown, batch.numel() * self.step_seconds / 60))
        stats = {
            "reward": float(batch["next", "reward"].mean()),
            "throws_per_minute": sum(t for t, _ in self.recent) / sum(m for _, m in self.recent),
        }
        done = batch["next", "done"].squeeze(-1)
        if done.any():
            finished = batch["next"][done]
            stats["return"] = float(finished["episode_reward"].mean())
            stats["throws"] = float(finished["throws"].double().mean())
            stats["catches"] = float(finished["catches"].double().mean())
            stats["episode_seconds"] = float(finished["time"].double().mean())
        return stats
