"""The default viewer layout, sent once per recording so a new user sees something useful at once.

The 3D scene on the left; on the right the episode's ball height over the threshold, and below it
the learning curves side by side (one plot per metric group that the run logs).
"""

from __future__ import annotations

from collections.abc import Sequence

import rerun.blueprint as rrb

from jugglerl.recording.names import PLOTS, SIM_TIME, WORLD, join


def juggling_blueprint(episode_root: str = "", metric_groups: Sequence[str] = ()) -> rrb.Blueprint:
    """Layout for an episode recorded under ``episode_root`` and metrics under ``metric_groups``.

    ``metric_groups`` are top-level entity paths such as ``("train", "eval")``; each gets its own
    time-series plot on the ``step`` timeline.
    """
    episode = [
        rrb.TimeSeriesView(origin=join(episode_root, PLOTS), name="ball height (m)"),
    ]
    curves = [rrb.TimeSeriesView(origin=group, name=group) for group in metric_groups]
    right = episode + ([rrb.Horizontal(*curves)] if curves else [])
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin=join(episode_root, WORLD), name="scene"),
            rrb.Vertical(*right),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline=SIM_TIME),
    )
