"""How juggling policies hold up when the world is not as planned.

Each *perturbation family* varies one env argument (``jugglerl_envs.perturbations``): the ball's
start offset, its mass, its radius, the arm servos' gain, the speed of random kicks of the ball in
flight. ``measure`` runs every policy (open-loop commands and trained checkpoints alike, through
``load_policy``) for ``seeds`` episodes at the nominal env and at each magnitude of each family, a
policy's episodes batched (``EpisodePool``) in worker processes; ``summarise`` turns the episodes
into rows of mean throws, fraction of the policy's own nominal throws and time to drop, and
``breaking_points`` finds, per family, the first magnitude where a reference open-loop policy falls
below a fraction of its nominal, and what the others keep there. ``markdown``/``plot`` render them
for docs/results/ and the run directory.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from omegaconf import DictConfig, OmegaConf

from jugglerl.cluster.episode_pool import EpisodePool, EpisodeTask
from jugglerl.config.envs import make_juggle_env
from jugglerl.policies.loading import load_policy
from jugglerl.runs.files import write_atomically

NOMINAL = "nominal"


@dataclass(frozen=True)
class Family:
    """Perturbations that set env argument ``key`` to each of ``magnitudes`` (in ``unit``), with
    ``fixed`` env arguments alongside (e.g. the kick rate for kick speeds); ``nominal`` is the
    key's value in the unperturbed env."""

    name: str
    key: str
    magnitudes: tuple[float, ...]
    nominal: float
    unit: str = ""
    fixed: Mapping[str, float] = field(default_factory=dict)

    def overrides(self, magnitude: float) -> dict[str, float]:
        return {**self.fixed, self.key: magnitude}


def families_from_config(
    cfg: DictConfig, env_cfg: DictConfig, select: Iterable[str] = ()
) -> list[Family]:
    """Families from the ``families`` mapping of ``configs/robustness.yaml`` (only those named in
    ``select``, when it is not empty) on the env of ``env_cfg``."""
    select = list(select)
    unknown = set(select) - set(cfg)
    if unknown:
        raise ValueError(f"select={sorted(unknown)}: no such families; valid: {', '.join(cfg)}")
    families = []
    for name, family in cfg.items():
        if select and name not in select:
            continue
        unknown = set(family) - {"key", "magnitudes", "unit", "fixed"}
        if unknown or "key" not in family or not family.get("magnitudes"):
            raise ValueError(
                f"families.{name}: needs key and a non-empty magnitudes list (and optional unit,"
                f" fixed); got {sorted(family)}"
            )
        if family.key not in env_cfg:
            raise ValueError(f"families.{name}.key={family.key} is not an env argument")
        try:
            magnitudes = tuple(float(m) for m in family.magnitudes)
        except (TypeError, ValueError):
            raise ValueError(
                f"families.{name}.magnitudes={list(family.magnitudes)} must be numbers"
            ) from None
        families.append(
            Family(
                name=str(name),
                key=str(family.key),
                magnitudes=magnitudes,
                nominal=float(env_cfg[family.key]),
                unit=str(family.get("unit", "")),
                fixed=dict(family.get("fixed") or {}),
            )
        )
    return families


@dataclass(frozen=True)
class Condition:
    """One env setting: ``nominal`` or a family at a magnitude."""

    family: str
    magnitude: float | None
    overrides: Mapping[str, float]


def conditions(families: Iterable[Family]) -> list[Condition]:
    """The nominal condition, then every family at each of its magnitudes."""
    found = [Condition(NOMINAL, None, {})]
    for family in families:
        found += [Condition(family.name, m, family.overrides(m)) for m in family.magnitudes]
    return found


# --- episodes, in worker processes -------------------------------------------------------------
def check_policies(policies: Iterable[str], env_cfg: DictConfig) -> None:
    """Load each policy once here, so that a bad name fails before any work (``ValueError``)."""
    env = make_juggle_env(env_cfg)
    for spec in policies:
        load_policy(spec, env)
    env.close()


def measure(
    policies: list[str],
    env_cfg: DictConfig,
    families: list[Family],
    seeds: int,
    duration: float,
    workers: int = 0,
    on_episode: Callable[[], None] | None = None,
    cluster: DictConfig | None = None,
) -> list[dict]:
    """Episodes of every policy under every condition, env seeds ``0..seeds-1``.

    Returns one record per (policy, condition): ``policy``, ``family``, ``magnitude``,
    ``throws`` and ``seconds_up`` (lists over seeds). ``workers`` processes (0: all cores), or
    the Ray cluster of ``cluster`` (a ``configs/cluster`` group);
    ``on_episode`` is called as each episode finishes (progress bars).
    """
    if seeds < 1:
        raise ValueError(f"seeds={seeds} must be >= 1")
    check_policies(policies, env_cfg)
    plan = [(spec, condition) for spec in policies for condition in conditions(families)]
    base = {**OmegaConf.to_container(env_cfg, resolve=True), "duration": duration}
    tasks = [
        EpisodeTask({**base, **condition.overrides}, spec, seed)
        for spec, condition in plan
        for seed in range(seeds)
    ]
    with EpisodePool(workers, cluster) as pool:
        results = pool.run(tasks, None if on_episode is None else lambda _: on_episode())
    records = []  # by condition, then policy (the pool ran each policy's episodes together)
    order = [(condition, spec) for condition in conditions(families) for spec in policies]
    for condition, spec in order:
        index = plan.index((spec, condition))
        episodes = results[index * seeds : (index + 1) * seeds]
        records.append(
            {
                "policy": spec,
                "family": condition.family,
                "magnitude": condition.magnitude,
                "throws": [episode.throws for episode in episodes],
                "seconds_up": [episode.duration for episode in episodes],
            }
        )
    return records


# --- summaries --------------------------------------------------------------------------------
def summarise(records: list[dict]) -> list[dict]:
    """Rows with ``mean_throws``, ``fraction_of_nominal`` (of the policy's own nominal mean
    throws; ``None`` when that is 0) and ``mean_seconds_up`` (time to drop; a kept ball counts
    the whole episode)."""
    nominal = {r["policy"]: float(np.mean(r["throws"])) for r in records if r["family"] == NOMINAL}
    rows = []
    for record in records:
        mean_throws = float(np.mean(record["throws"]))
        base = nominal[record["policy"]]
        rows.append(
            {
                "policy": record["policy"],
                "family": record["family"],
                "magnitude": record["magnitude"],
                "mean_throws": mean_throws,
                "fraction_of_nominal": mean_throws / base if base > 0 else None,
                "mean_seconds_up": float(np.mean(record["seconds_up"])),
            }
        )
    return rows


def throws_lines(rows: list[dict]) -> dict[tuple[str, str], list[float]]:
    """Per (family, policy), the mean throws at the nominal env then at each magnitude in turn:
    the lines of the plot and of the recording."""
    nominal = {r["policy"]: r["mean_throws"] for r in rows if r["family"] == NOMINAL}
    lines: dict[tuple[str, str], list[float]] = {}
    for row in rows:
        if row["family"] != NOMINAL:
            line = lines.setdefault((row["family"], row["policy"]), [nominal[row["policy"]]])
            line.append(row["mean_throws"])
    return lines


def breaking_points(rows: list[dict], reference: str, fraction: float) -> list[dict]:
    """Per family, the first magnitude where ``reference`` keeps under ``fraction`` of its
    nominal throws, with every policy's fraction there; families where it never breaks are
    left out."""
    points = []
    for family in dict.fromkeys(r["family"] for r in rows if r["family"] != NOMINAL):
        at = [r for r in rows if r["family"] == family]
        broken = [
            r["magnitude"]
            for r in at
            if r["policy"] == reference
            and r["fraction_of_nominal"] is not None
            and r["fraction_of_nominal"] < fraction
        ]
        if not broken:
            continue
        kept = {r["policy"]: r["fraction_of_nominal"] for r in at if r["magnitude"] == broken[0]}
        points.append({"family": family, "magnitude": broken[0], "kept": kept})
    return points


def _percent(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.0%}"


def markdown(rows: list[dict], families: list[Family], points: list[dict]) -> str:
    """The results table (and the breaking points) as Markdown."""
    units = {family.name: family.unit for family in families}
    lines = [
        "| perturbation | magnitude | policy | mean throws | of nominal | ball up (s) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for row in rows:
        magnitude = ""
        if row["magnitude"] is not None:
            magnitude = f"{row['magnitude']:g} {units[row['family']]}"
        lines.append(
            f"| {row['family']} | {magnitude.strip()} | {row['policy']} |"
            f" {row['mean_throws']:.1f} | {_percent(row['fraction_of_nominal'])} |"
            f" {row['mean_seconds_up']:.1f} |"
        )
    if points:
        policies = list(points[0]["kept"])
        lines += [
            "",
            "| perturbation | breaks the reference at | " + " | ".join(policies) + " |",
            "| --- | --- | " + " | ".join("---" for _ in policies) + " |",
        ]
        for point in points:
            magnitude = f"{point['magnitude']:g} {units[point['family']]}".strip()
            kept = " | ".join(_percent(point["kept"][p]) for p in policies)
            lines.append(f"| {point['family']} | {magnitude} | {kept} |")
    return "\n".join(lines) + "\n"


def plot(rows: list[dict], families: list[Family], path: Path) -> Path:
    """Mean throws against magnitude as a PNG: one panel per family, one line per policy from
    its nominal throws (at the family's nominal value) through each magnitude."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines = throws_lines(rows)
    figure, axes = plt.subplots(
        1, len(families), figsize=(3.2 * len(families), 3.0), squeeze=False, sharey=True
    )
    for axis, family in zip(axes[0], families, strict=True):
        magnitudes = (family.nominal, *family.magnitudes)
        for (name, policy), throws in lines.items():
            if name == family.name:
                xs, ys = zip(*sorted(zip(magnitudes, throws, strict=True)), strict=True)
                axis.plot(xs, ys, marker="o", label=policy)
        axis.set_title(family.name)
        axis.set_xlabel(f"{family.key} ({family.unit})" if family.unit else family.key)
        axis.grid(alpha=0.3)
    axes[0][0].set_ylabel("mean throws")
    axes[0][-1].legend(fontsize="small")
    figure.tight_layout()
    try:
        write_atomically(Path(path), lambda file: figure.savefig(file, dpi=100, format="png"))
    finally:
        plt.close(figure)
    return path
