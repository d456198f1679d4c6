"""The flat parameter vector θ of a via-point command, and the constraints a sample must meet.

Layout of θ for a command with ``p`` via-points (length ``1 + 3 p``)::

    index   0        1     2      3      4     5      6     ...  3p-2   3p-1   3p
    value   d        t_1   a2_1   a3_1   t_2   a2_2   a3_2  ...  t_p    a2_p   a3_p
            cycle s  time  lift   elbow  ...

Times in seconds from the start of the cycle, angles in radians (servo setpoints of
``shoulder_lift_joint`` and ``elbow_joint``). Not searched: the pan angle (the start command's) and
the lead-in before the first cycle (``algo.lead_in``).

A Gaussian sample is any real vector; ``ViaPointConstraints.project`` maps it onto a valid command:
cycle in ``[min_cycle, max_cycle]``, via-points sorted by time (each moves with its angles), times
at least ``min_gap`` apart inside ``[0, d)``, and angles inside the servos' control ranges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from jugglerl.commands import ViaPointCommand

CYCLE, TIME, LIFT, ELBOW = "cycle", "time", "lift", "elbow"
#: Components of θ, in the order their stds are given.
COMPONENTS = (CYCLE, TIME, LIFT, ELBOW)


def n_via_points(params: torch.Tensor) -> int:
    size = params.shape[-1]
    if size < 4 or (size - 1) % 3:
        raise ValueError(f"a parameter vector has 1 + 3 p entries, got {size}")
    return (size - 1) // 3


def command_to_params(command: ViaPointCommand) -> torch.Tensor:
    """θ of ``command`` (float64)."""
    return torch.tensor([command.cycle, *np.ravel(command.via_points)], dtype=torch.float64)


def params_to_command(
    params: torch.Tensor, pan: float = 0.0, name: str = "dps", lead_in: float = 0.0
) -> ViaPointCommand:
    """The command of a valid θ (see ``ViaPointConstraints.project``); ``pan`` and ``lead_in``
    are not part of θ."""
    values = params.detach().cpu().double().tolist()
    points = tuple(tuple(values[1 + 3 * i : 4 + 3 * i]) for i in range(n_via_points(params)))
    return ViaPointCommand(values[0], points, pan, lead_in, name=name)


def component_stds(n_points: int, stds: dict[str, float]) -> torch.Tensor:
    """Per-entry stds of θ from one std per component (``cycle``, ``time``, ``lift``, ``elbow``)."""
    missing = set(COMPONENTS) - set(stds)
    if missing:
        raise ValueError(f"missing stds for {sorted(missing)}; give {', '.join(COMPONENTS)}")
    per_point = [stds[TIME], stds[LIFT], stds[ELBOW]]
    values = torch.tensor([stds[CYCLE], *per_point * n_points], dtype=torch.float64)
    if not torch.all(values >= 0):
        raise ValueError(f"stds must be >= 0, got {dict(stds)}")
    return values


@dataclass(frozen=True)
class ViaPointConstraints:
    """Bounds a command must respect. Seconds and radians.

    ``lift_range``/``elbow_range``: servo control ranges (``from_model`` reads them from MuJoCo).
    """

    min_cycle: float
    max_cycle: float
    min_gap: float
    lift_range: tuple[float, float]
    elbow_range: tuple[float, float]

    def __post_init__(self):
        if not 0 < self.min_cycle <= self.max_cycle:
            raise ValueError(
                f"need 0 < min_cycle <= max_cycle, got {self.min_cycle} and {self.max_cycle}"
            )
        if self.min_gap <= 0:
            raise ValueError(f"min_gap must be > 0 s, got {self.min_gap}")

    @classmethod
    def from_model(cls, model, min_cycle: float, max_cycle: float, min_gap: float):
        """Angle ranges of the ``shoulder_lift`` and ``elbow`` actuators of a MuJoCo model."""
        lift = tuple(float(v) for v in model.actuator("shoulder_lift").ctrlrange)
        elbow = tuple(float(v) for v in model.actuator("elbow").ctrlrange)
        return cls(min_cycle, max_cycle, min_gap, lift, elbow)

    def check(self, n_points: int) -> None:
        """Raise if ``n_points`` via-points cannot fit ``min_gap`` apart in the shortest cycle."""
        if n_points * self.min_gap > self.min_cycle:
            raise ValueError(
                f"{n_points} via-points {self.min_gap} s apart do not fit in"
                f" min_cycle={self.min_cycle} s"
            )

    def project(self, params: torch.Tensor) -> torch.Tensor:
        """Valid θ nearest in spirit to ``params`` (``[..., 1 + 3p]``); valid θ are unchanged."""
        p = n_via_points(params)
        self.check(p)
        cycle = params[..., :1].clamp(self.min_cycle, self.max_cycle)
        points = params[..., 1:].reshape(*params.shape[:-1], p, 3)
        order = torch.argsort(points[..., 0], dim=-1, stable=True)
        points = torch.take_along_dim(points, order[..., None], dim=-2)
        slots = torch.arange(p, dtype=params.dtype, device=params.device)
        # room for the earlier points before, and the later ones after (times stay below d)
        lowest = slots * self.min_gap
        highest = cycle - (p - slots) * self.min_gap
        times = torch.minimum(torch.maximum(points[..., 0], lowest), highest)
        for i in range(1, p):  # sorted and clamped: pushing each up by the gap keeps it <= highest
            times[..., i] = torch.maximum(times[..., i], times[..., i - 1] + self.min_gap)
        lift = points[..., 1].clamp(*self.lift_range)
        elbow = points[..., 2].clamp(*self.elbow_range)
        points = torch.stack([times, lift, elbow], dim=-1)
        return torch.cat([cycle, points.flatten(-2)], dim=-1)

    def violations(self, params: torch.Tensor) -> list[str]:
        """What is wrong with one θ (empty when valid): for tests and error messages."""
        cycle = float(params[0])
        points = params[1:].reshape(-1, 3)
        problems = []
        if not self.min_cycle <= cycle <= self.max_cycle:
            problems.append(f"cycle {cycle} outside [{self.min_cycle}, {self.max_cycle}]")
        times = points[:, 0]
        if times[0] < 0 or times[-1] >= cycle:
            problems.append(f"times {times.tolist()} not inside [0, {cycle})")
        if torch.any(torch.diff(times) < self.min_gap - 1e-9):
            problems.append(f"times {times.tolist()} closer than {self.min_gap} s")
        for name, values, (low, high) in (
            (LIFT, points[:, 1], self.lift_range),
            (ELBOW, points[:, 2], self.elbow_range),
        ):
            if torch.any(values < low) or torch.any(values > high):
                problems.append(f"{name} {values.tolist()} outside [{low}, {high}]")
        return problems
