"""A whole sequence from above, in the world frame: every ground-truth trajectory, every track of a tracker,
and where its identity switches happened."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow as pa  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from simrig.dataset import Dataset  # noqa: E402
from simrig.dataset.outputs import save_figure  # noqa: E402
from simrig.figures.mosaic import identity_colour  # noqa: E402
from simrig.road import dash_segments  # noqa: E402

MARGIN_M = 10.0
"""[m] around the ground-truth and ego trajectories."""


def _paths(ids: np.ndarray, frames: np.ndarray, xy: np.ndarray) -> dict[int, np.ndarray]:
    """``(K, 2)`` world (x, y) [m] per id, in frame order, from rows of (id, frame, (x, y))."""
    order = np.lexsort((frames, ids))
    ids, xy = ids[order], xy[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    return {int(ids[s]): xy[s:e] for s, e in zip(starts, np.r_[starts[1:], len(ids)], strict=True)}


def plot_bev(dataset: Dataset, tracks3d: pa.Table | None, switches: list[tuple[int, int]], title: str,
             out: Path) -> Path:
    """Ground truth (grey), the ego (black), tracks (a colour per track id) and identity switches (red ×,
    each with its number in ``switches``, a list of (frame, actor id) in the order they are numbered)."""
    truth = dataset.ground_truth
    truth_paths = _paths(truth.actor_id, truth.frame, truth.boxes[:, :2])
    points = [np.array([(ego.x, ego.y) for ego in truth.egos]).reshape(-1, 2)]
    points += list(truth_paths.values())
    everything = np.concatenate(points)  # the view fits the road traffic; a track that wanders off is cut
    low, high = everything.min(axis=0) - MARGIN_M, everything.max(axis=0) + MARGIN_M
    span = high - low
    equal = span.max() / max(span.min(), 1e-9) <= 6.0
    width = 16.0
    height = float(np.clip(width * span[1] / span[0], 3.5, 12.0)) if equal else 5.0
    figure, axis = plt.subplots(figsize=(width, height + 0.8), dpi=100)
    markings = dataset.road_markings()
    if markings is not None:
        segments = [dash_segments(line, dashed) for line, dashed in zip(markings.lines, markings.dashed, strict=True)]
        axis.add_collection(LineCollection(np.concatenate(segments), colors="0.8", linewidths=0.6))
    for path in truth_paths.values():
        axis.plot(path[:, 0], path[:, 1], color="0.55", linewidth=2.4, alpha=0.5, solid_capstyle="round")
    axis.plot(points[0][:, 0], points[0][:, 1], color="black", linewidth=1.5, label="ego")
    if tracks3d is not None:
        xy = np.column_stack([tracks3d.column("x").to_numpy(), tracks3d.column("y").to_numpy()])
        for track_id, path in _paths(tracks3d.column("track_id").to_numpy(), tracks3d.column("frame").to_numpy(),
                                     xy).items():
            axis.plot(path[:, 0], path[:, 1], color=identity_colour(track_id), linewidth=0.9)
    for number, (frame, actor) in enumerate(switches, start=1):
        try:
            row = truth.rows_of(np.array([frame]), np.array([actor]))[0]
        except KeyError:
            continue
        x, y = truth.boxes[row, :2]
        axis.plot(x, y, marker="x", color="red", markersize=10, markeredgewidth=2.2,
                  label="identity switch (numbered)" if number == 1 else None)
        axis.annotate(str(number), (x, y), textcoords="offset points", xytext=(4, 5), fontsize=8, color="darkred")
    axis.set_xlim(low[0], high[0])
    axis.set_ylim(low[1], high[1])
    axis.set_aspect("equal" if equal else "auto")
    axis.set_xlabel("world x [m]")
    axis.set_ylabel("world y [m]")
    axis.set_title(title + ("" if equal else " (axes not to scale)"), fontsize=10)
    axis.plot([], [], color="0.55", linewidth=2.4, alpha=0.5, label="ground truth")
    axis.plot([], [], color="tab:blue", linewidth=0.9, linestyle="-" if tracks3d is not None else "none",
              label="tracks (a colour per id)" if tracks3d is not None else "no 3D tracks (a 2D tracker)")
    axis.legend(fontsize=8, loc="upper left")
    figure.tight_layout()
    save_figure(figure, out)
    plt.close(figure)
    return out
