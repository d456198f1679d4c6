"""Screenshots of the real rerun viewer, and what its state says, for the screenshot tests.

``screenshot`` runs ``../shared/tools/rrd-screenshot`` (relative to the repository root): the
viewer headless on Mesa's CPU Vulkan driver (Debian package ``mesa-vulkan-drivers``). It skips
the test, saying why, where the tool or the driver is missing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import rerun.blueprint as rrb
from cli import ROOT
from rerun.chunk import RrdReader

TOOL = ROOT.parent / "shared" / "tools" / "rrd-screenshot"
#: Where Debian's mesa-vulkan-drivers installs the CPU (lavapipe) driver's manifest.
CPU_VULKAN_DRIVERS = Path("/usr/share/vulkan/icd.d")


def screenshot(recording: Path, out: Path, **env: str) -> dict:
    """PNG of the viewer showing ``recording`` at ``out``; returns the viewer's state.

    ``env``: the tool's settings (``AT="end"``, ``TIMELINE="step"``, ``SIZE=...``).
    """
    if not TOOL.exists():
        pytest.skip(f"no screenshot tool at {TOOL}")
    if not any(CPU_VULKAN_DRIVERS.glob("lvp_icd*.json")):
        pytest.skip("no CPU Vulkan driver: apt-get install mesa-vulkan-drivers")
    result = subprocess.run(
        [str(TOOL), str(recording), str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=os.environ | {"PY": sys.executable} | env,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(Path(f"{out}.state.json").read_text())


def opening_views(blueprint: rrb.Blueprint) -> list[rrb.View]:
    """The views ``blueprint`` shows on opening: all of them, but only the active tab's of tabs."""

    def shown(item) -> list[rrb.View]:
        if isinstance(item, rrb.View):
            return [item]
        contents = item.contents
        if isinstance(item, rrb.Tabs):
            contents = [contents[item.active_tab or 0]]
        return [view for part in contents for view in shown(part)]

    return shown(blueprint.root_container)


def views_without_data(recording: Path, views: list[rrb.View], timeline: str) -> list[str]:
    """Names of the ``views`` with nothing to show on ``timeline``.

    A text view needs its document (static); a plot or a 3D view needs data logged on the
    timeline (a scene whose bodies move only on another timeline stands still here).
    """
    chunks = [
        (chunk.entity_path.strip("/"), set(chunk.timeline_names))
        for chunk in RrdReader(recording).stream()
    ]
    return [
        str(view.name) for view in views if not any(has_data(view, c, timeline) for c in chunks)
    ]


def has_data(view: rrb.View, chunk: tuple[str, set[str]], timeline: str) -> bool:
    """The ``(entity, timelines)`` chunk is data ``view`` draws on ``timeline``."""
    entity, timelines = chunk
    static_is_enough = isinstance(view, rrb.TextDocumentView)
    return shows(view, entity) and (static_is_enough or timeline in timelines)


def shows(view: rrb.View, entity: str) -> bool:
    """``entity`` is among the entities ``view``'s contents query."""
    included, excluded = queried_paths(view)
    return matches(entity, included) and not matches(entity, excluded)


def queried_paths(view: rrb.View) -> tuple[list[str], list[str]]:
    """The entity paths a view's contents include and exclude (``+ path`` / ``- path``)."""
    contents = [view.contents] if isinstance(view.contents, str) else list(view.contents)
    origin = str(view.origin).strip("/")
    included, excluded = [], []
    for expression in contents:
        sign, _, path = (
            expression.partition(" ") if expression[0] in "+-" else ("+", "", expression)
        )
        path = path.replace("$origin", origin).strip("/")
        (excluded if sign == "-" else included).append(path)
    return included, excluded


def matches(entity: str, paths: list[str]) -> bool:
    """``entity`` is one of ``paths``, or under one ending in ``/**``."""
    for path in paths:
        if path.endswith("**"):
            prefix = path.removesuffix("**").strip("/")
            if not prefix or entity == prefix or entity.startswith(f"{prefix}/"):
                return True
        elif entity == path:
            return True
    return False
