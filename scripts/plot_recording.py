"""Draw a recording's ball-height plot as a PNG, without a viewer (headless machines, READMEs).

    python scripts/plot_recording.py outputs/evaluate/<run>/episode.rrd [--out plot.png]
        [--root ""] [--seconds 30]

Reads ``<root>/plots/ball_height`` (and, from an episode of several balls, ``ball_1_height``, ...),
``threshold`` and ``throws`` back from the ``.rrd`` with rerun's reader and draws them as the
viewer's plot does (red height, further balls in their colours, blue threshold, yellow throw
markers) over the first ``--seconds`` of simulated time. Prints what it read.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from jugglerl.recording.episode import HEIGHT_COLOUR, THRESHOLD_COLOUR, THROW_COLOUR
from jugglerl.recording.names import PLOTS, SIM_TIME, join
from jugglerl.recording.reading import column
from jugglerl_envs.scene import EXTRA_BALL_COLOURS, ball_name

WIDTH, HEIGHT, MARGIN = 900, 300, 20


def read_series(path: Path, entity: str) -> tuple[np.ndarray, np.ndarray]:
    """(sim_time in s, value) of a scalar series, sorted by time."""
    times, values = column(path, entity, "Scalars:scalars", SIM_TIME)
    if not len(times):
        raise SystemExit(f"error: no scalar series at {entity!r} in {path}")
    return times, values


def ball_heights(path: Path, plots: str) -> list[tuple[np.ndarray, np.ndarray, list[int], str]]:
    """Each recorded ball's height series, drawn as a line in its colour (the first in red)."""
    series = [(*read_series(path, join(plots, "ball_height")), HEIGHT_COLOUR, "line")]
    for ball, rgba in enumerate(EXTRA_BALL_COLOURS, start=1):
        times, values = column(
            path, join(plots, f"{ball_name(ball)}_height"), "Scalars:scalars", SIM_TIME
        )
        if not len(times):
            break
        colour = [round(255 * float(c)) for c in rgba.split()[:3]]
        series.append((times, values, colour, "line"))
    return series


def draw(series: list[tuple[np.ndarray, np.ndarray, list[int], str]], seconds: float) -> np.ndarray:
    """White canvas with each (times, values, colour, style) drawn; style 'line' or 'marker'."""
    image = np.full((HEIGHT, WIDTH, 3), 255, dtype=np.uint8)
    top = max(float(values.max()) for _, values, _, _ in series) * 1.05

    def pixel(t, v):
        x = MARGIN + (WIDTH - 2 * MARGIN) * np.asarray(t) / seconds
        y = HEIGHT - MARGIN - (HEIGHT - 2 * MARGIN) * np.asarray(v) / top
        return x.round().astype(int), y.round().astype(int)

    image[HEIGHT - MARGIN, MARGIN : WIDTH - MARGIN] = 0  # time axis
    image[MARGIN : HEIGHT - MARGIN, MARGIN] = 0  # height axis (0 at the bottom)
    for times, values, colour, style in series:
        keep = times <= seconds
        xs, ys = pixel(times[keep], values[keep])
        if style == "marker":
            for x, y in zip(xs, ys, strict=True):
                for d in range(-5, 6):  # a diamond
                    w = 5 - abs(d)
                    image[y + d, x - w : x + w + 1] = colour
            continue
        for x0, y0, x1, y1 in zip(xs[:-1], ys[:-1], xs[1:], ys[1:], strict=True):  # segments
            steps = max(abs(x1 - x0), abs(y1 - y0), 1)
            for k in range(steps + 1):
                x, y = x0 + (x1 - x0) * k // steps, y0 + (y1 - y0) * k // steps
                image[y - 1 : y + 1, x - 1 : x + 1] = colour
    return image


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", type=Path)
    parser.add_argument("--out", type=Path, default=None, help="default: <recording>.png")
    parser.add_argument("--root", default="", help="entity root of the episode, e.g. eval/ep_3")
    parser.add_argument("--seconds", type=float, default=30.0)
    args = parser.parse_args()
    if not args.recording.is_file():
        raise SystemExit(f"error: no recording at {args.recording}")

    plots = join(args.root, PLOTS)
    heights = ball_heights(args.recording, plots)
    threshold = read_series(args.recording, join(plots, "threshold"))
    threshold = (np.array([0.0, args.seconds]), threshold[1][:2])
    throws = read_series(args.recording, join(plots, "throws"))
    image = draw(
        [
            (*threshold, THRESHOLD_COLOUR, "line"),
            *heights,
            (*throws, THROW_COLOUR, "marker"),
        ],
        args.seconds,
    )
    out = args.out or args.recording.with_suffix(".png")
    iio.imwrite(out, image)
    shown = int((throws[0] <= args.seconds).sum())
    print(
        f"{len(heights)} ball(s), {len(heights[0][0])} heights each, {len(throws[0])} throws"
        f" ({shown} in the first {args.seconds:g} s) -> {out}"
    )


if __name__ == "__main__":
    main()
