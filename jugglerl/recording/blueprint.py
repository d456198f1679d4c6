"""Default viewer layouts, one per kind of recording, so that a recording shows its run on opening.

- ``episode_blueprint``: an evaluated episode (``evaluate.py``). Opens on ``sim_time``: the 3D
  scene with the camera on the arm and the ball; the ball height over the threshold with a marker
  per throw; the episode's metrics and the run's config as text.
- ``training_blueprint``: a training run. Opens on ``step`` with the learning curves of the whole
  run, one panel per kind of quantity (``OFFPOLICY_CURVES``, ``SEARCH_CURVES``), and the config; the
  latest recorded episode (on ``sim_time``) in a second tab.

The viewer's side panels start collapsed, so the views get the window, and the time cursor starts
at the end of the recording ("following"), where the whole run has arrived.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import rerun as rr
import rerun.blueprint as rrb

from jugglerl.recording.names import (
    DPS,
    EVAL,
    HPARAMS,
    PLOTS,
    SIM_TIME,
    STEP,
    SUMMARY,
    TRAIN,
    WORLD,
    join,
)

#: Camera of the 3D view, in metres in the world frame. The arm's base is at the origin, the cup
#: starts at (-0.45, -0.13, 0.49) and the ball flies up to ≈ 1.05 m above it. Seen from the side
#: (-y), the lift and elbow motions that throw the ball lie in the picture's plane.
EYE = (0.5, -1.9, 1.55)
LOOK_AT = (-0.25, -0.1, 0.55)
#: Room above the threshold in the ball-height plot (m), so the threshold line and the throw
#: markers on it are not drawn on the plot's edge.
HEADROOM = 0.3

#: Line colours of a panel's metrics, in order: distinct within a panel, whatever the paths.
PALETTE = ([230, 60, 60], [40, 160, 255], [255, 200, 0], [80, 200, 120], [200, 120, 255])

#: y-axis of a fraction: 0 and 1 drawn inside the plot, not on its edges.
FRACTION = (-0.05, 1.05)

WHOLE_TIMELINE = rrb.TimeRange(
    start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.infinite()
)


@dataclass(frozen=True)
class Curve:
    """A learning-curve panel: metrics of one kind of quantity, on one y-axis.

    ``metrics`` are entity paths (``train/loss_critic``, or ``dps/**`` for a subtree), less those
    in ``excluded``; ``legend`` is the corner where the curves are least likely to run (rising
    curves leave the top left free), or ``None`` to hide the legend of a single-metric panel,
    whose name says what it shows; ``y_range`` fixes the y-axis of a bounded quantity (a
    fraction reads as one from 0 to 1), ``None`` fits it to the data.
    """

    name: str
    metrics: tuple[str, ...]
    legend: rrb.Corner2D | None = rrb.Corner2D.LeftTop
    excluded: tuple[str, ...] = ()
    y_range: tuple[float, float] | None = None


#: Off-policy training (``train/*`` per collected batch, ``eval/*`` per evaluation; step = env
#: frames): DDPG, TD3 and behaviour cloning.
OFFPOLICY_CURVES = (
    Curve("throws per episode", (f"{TRAIN}/throws", f"{EVAL}/mean_throws")),
    Curve("throws per minute (training)", (f"{TRAIN}/throws_per_minute",), legend=None),
    Curve("stage (index in algo.stages)", (f"{TRAIN}/stage",), legend=None),
    Curve("catches per episode", (f"{TRAIN}/catches", f"{EVAL}/mean_catches")),
    Curve("time up per episode (s)", (f"{TRAIN}/episode_seconds", f"{EVAL}/mean_time_to_drop")),
    Curve("catch rate (evaluation)", (f"{EVAL}/catch_rate",), legend=None, y_range=FRACTION),
    Curve("return per episode (training)", (f"{TRAIN}/return",), legend=None),
    Curve("reward per step (training)", (f"{TRAIN}/reward",), legend=None),
    Curve("critic loss", (f"{TRAIN}/loss_critic",), legend=None),
    Curve(
        "Q value and actor losses",
        (f"{TRAIN}/q_value", f"{TRAIN}/loss_actor", f"{TRAIN}/loss_bc"),
    ),
)


#: PPO (``algo=ppo``): the episodes and rewards of training, the policy's spread and the
#: update's own measures.
ONPOLICY_CURVES = (
    Curve("throws per episode", (f"{TRAIN}/throws", f"{EVAL}/mean_throws")),
    Curve("throws per minute (training)", (f"{TRAIN}/throws_per_minute",), legend=None),
    Curve("time up per episode (s)", (f"{TRAIN}/episode_seconds", f"{EVAL}/mean_time_to_drop")),
    Curve("catch rate (evaluation)", (f"{EVAL}/catch_rate",), legend=None, y_range=FRACTION),
    Curve("return per episode (training)", (f"{TRAIN}/return",), legend=None),
    Curve(
        "reward per step (training)",
        (f"{TRAIN}/reward", f"{TRAIN}/reward_throws", f"{TRAIN}/reward_dense"),
    ),
    Curve("policy σ (normalised action units)", (f"{TRAIN}/sigma",), legend=None),
    Curve("KL and clip fraction", (f"{TRAIN}/kl_approx", f"{TRAIN}/clip_fraction")),
    Curve("critic loss", (f"{TRAIN}/loss_critic",), legend=None),
    Curve("value and objective", (f"{TRAIN}/value", f"{TRAIN}/loss_objective")),
    Curve("frames per second (collection)", (f"{TRAIN}/frames_per_second",), legend=None),
)


def with_perturbed(curves: tuple[Curve, ...], conditions: Sequence[str]) -> tuple[Curve, ...]:
    """``curves``, and with perturbed evaluation ``conditions`` (``eval.perturbed``'s names) a
    panel of their throws next to the nominal evaluation's."""
    if not conditions:
        return curves
    throws = (f"{EVAL}/mean_throws", *(f"{EVAL}/{name}/mean_throws" for name in conditions))
    return (*curves, Curve("throws per evaluation episode, perturbed", throws))


def offpolicy_curves(conditions: Sequence[str] = ()) -> tuple[Curve, ...]:
    """``OFFPOLICY_CURVES`` (and the perturbed evaluations' throws, ``with_perturbed``)."""
    return with_perturbed(OFFPOLICY_CURVES, conditions)


def onpolicy_curves(conditions: Sequence[str] = ()) -> tuple[Curve, ...]:
    """``ONPOLICY_CURVES`` (and the perturbed evaluations' throws, ``with_perturbed``)."""
    return with_perturbed(ONPOLICY_CURVES, conditions)


#: Search metrics of the roll-outs (``dps/*``: direct policy search and the feedback-gain search;
#: step = roll-outs so far).
SEARCH_THROWS = tuple(f"{DPS}/{name}" for name in ("best_throws", "max_throws", "mean_throws"))
SEARCH_DROPPED = f"{DPS}/dropped_fraction"
SEARCH_CURVES = (
    Curve("throws per roll-out", SEARCH_THROWS),
    Curve("dropped fraction of the roll-outs", (SEARCH_DROPPED,), legend=None, y_range=FRACTION),
    # whatever else the search logs: the distribution's cycle (DPS) or mean gains (feedback)
    Curve("search distribution", (f"{DPS}/**",), excluded=(*SEARCH_THROWS, SEARCH_DROPPED)),
)


def episode_blueprint(threshold: float) -> rrb.Blueprint:
    """Layout of ``evaluate.py``'s ``episode.rrd``: the episode at the top level."""
    text = rrb.Horizontal(
        rrb.TextDocumentView(origin=SUMMARY, name="episode metrics"),
        rrb.TextDocumentView(origin=HPARAMS, name="config"),
    )
    scene, height = episode_views("", threshold)
    return rrb.Blueprint(
        rrb.Horizontal(scene, rrb.Vertical(height, text, row_shares=[3, 2]), column_shares=[3, 2]),
        rrb.TimePanel(timeline=SIM_TIME, state="collapsed", play_state="following"),
        *collapsed_side_panels(),
    )


def training_blueprint(
    curves: Sequence[Curve], episode_root: str | None = None, threshold: float = 1.0
) -> rrb.Blueprint:
    """Layout of a training run's ``train.rrd``: ``curves`` and the config on ``step``; with
    ``episode_root``, the episode recorded there in a tab (its ball height over ``threshold``,
    m; the env's default is 1 m)."""
    views = [curve_view(curve) for curve in curves]
    views.append(rrb.TextDocumentView(origin=HPARAMS, name="config"))
    columns = math.ceil(math.sqrt(len(views)))
    tabs = [rrb.Grid(*views, grid_columns=columns, name="learning curves")]
    if episode_root is not None:
        scene, height = episode_views(episode_root, threshold)
        tabs.append(
            rrb.Horizontal(scene, height, column_shares=[3, 2], name=f"episode {episode_root}")
        )
    return rrb.Blueprint(
        rrb.Tabs(*tabs, active_tab=0),
        rrb.TimePanel(timeline=STEP, state="collapsed", play_state="following"),
        *collapsed_side_panels(),
    )


def curve_view(curve: Curve) -> rrb.TimeSeriesView:
    """A time series of ``curve.metrics`` over the whole ``step`` timeline, not a window.

    Each metric's line has a colour of its own and is named by its entity path
    (``train/throws`` and ``eval/mean_throws`` differ at a glance); a subtree keeps the viewer's.
    """
    legend = (
        rrb.PlotLegend(visible=False)
        if curve.legend is None
        else rrb.PlotLegend(corner=curve.legend, visible=True)
    )
    return rrb.TimeSeriesView(
        origin="/",
        contents=[f"+ {path}" for path in curve.metrics] + [f"- {path}" for path in curve.excluded],
        name=curve.name,
        plot_legend=legend,
        overrides={
            path: rr.SeriesLines(colors=[colour], names=[path])
            for path, colour in zip(curve.metrics, PALETTE, strict=False)  # at most 5 a panel
            if not path.endswith("/**")
        },
        axis_x=rrb.TimeAxis(view_range=WHOLE_TIMELINE),
        axis_y=None if curve.y_range is None else rrb.ScalarAxis(range=curve.y_range),
        time_ranges=rrb.VisibleTimeRange(STEP, range=WHOLE_TIMELINE),
    )


def episode_views(root: str, threshold: float) -> tuple[rrb.Spatial3DView, rrb.TimeSeriesView]:
    """The 3D scene and the ball-height plot of the episode recorded under ``root``."""
    scene = rrb.Spatial3DView(
        origin=join(root, WORLD),
        name="scene",
        eye_controls=rrb.EyeControls3D(position=EYE, look_target=LOOK_AT),
    )
    height = rrb.TimeSeriesView(
        origin=join(root, PLOTS),
        name="ball height (m)",
        axis_x=rrb.TimeAxis(view_range=WHOLE_TIMELINE),  # the whole episode, not a window
        axis_y=rrb.ScalarAxis(range=(0.0, threshold + HEADROOM)),
        # the ball never falls below the cup while juggling: the bottom right is free
        plot_legend=rrb.PlotLegend(corner=rrb.Corner2D.RightBottom, visible=True),
    )
    return scene, height


def collapsed_side_panels() -> tuple[rrb.BlueprintPanel, rrb.SelectionPanel]:
    """The blueprint tree and the selection panel folded away (one click opens them)."""
    return rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed")
