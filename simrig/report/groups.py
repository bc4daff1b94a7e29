"""How trackers are grouped in a report: by how they were scored. A tracker scored in 3D over every camera and
one scored in 2D on one camera give numbers on different ground truth, so they never share a table or an axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd


@dataclass(frozen=True)
class Group:
    """Trackers with ``scored`` equal to ``key``: the metric columns to show (column, heading) and the error
    dimension of their causes."""

    key: str
    title: str
    metrics: tuple[tuple[str, str], ...]
    curve_metrics: tuple[tuple[str, str], ...]
    dimension: str
    switches: str
    """The identity-switch column."""


def group_of(scored: str) -> Group:
    """The group of trackers scored as ``scored`` (``3d``; ``2d``: 2D-only trackers over every camera; or a
    camera name)."""
    if scored == "3d":
        return Group(
            "3d", "3D trackers, scored in 3D over every camera (HOTA, AssA, IDF1: their boxes projected into "
            "every camera)",
            (("2d_HOTA", "HOTA"), ("2d_AssA", "AssA"), ("2d_IDF1", "IDF1"), ("3d_AMOTA", "AMOTA"),
             ("3d_MOTA", "MOTA"), ("3d_IDS", "IDS"), ("3d_FRAG", "FRAG"), ("3d_PKL", "PKL"),
             ("3d_HZ_MISS", "HZ_MISS"), ("3d_HZ_FAKE", "HZ_FAKE")),
            (("2d_HOTA", "HOTA"), ("2d_AssA", "AssA"), ("3d_AMOTA", "AMOTA"), ("3d_IDS", "IDS per sequence"),
             ("3d_PKL", "PKL")),
            "3d", "3d_IDS")
    if scored == "2d":
        return Group(
            "2d", "2D trackers, scored in 2D over every camera (their own per-camera boxes)",
            (("2d_HOTA", "HOTA"), ("2d_AssA", "AssA"), ("2d_IDF1", "IDF1"), ("2d_MOTA", "MOTA"),
             ("2d_IDSW", "IDSW"), ("2d_Frag", "Frag")),
            (("2d_HOTA", "HOTA"), ("2d_AssA", "AssA"), ("2d_IDF1", "IDF1"), ("2d_IDSW", "IDSW per sequence")),
            "2d", "2d_IDSW")
    return Group(
        scored, f"Trackers scored in 2D on camera {scored} only",
        (("2d_HOTA", "HOTA"), ("2d_AssA", "AssA"), ("2d_IDF1", "IDF1"), ("2d_MOTA", "MOTA"),
         ("2d_IDSW", "IDSW"), ("2d_Frag", "Frag")),
        (("2d_HOTA", "HOTA"), ("2d_AssA", "AssA"), ("2d_IDF1", "IDF1"), ("2d_IDSW", "IDSW per sequence")),
        "2d", "2d_IDSW")


def groups(results: pd.DataFrame) -> list[Group]:
    """The groups present: 3D first, then 2D over every camera, then single cameras; a metric the results do not
    hold (a bench made before the planner-aware scores) is left out."""
    keys = sorted(set(results["scored"]), key=lambda key: (key != "3d", key != "2d", key))
    found = []
    for key in keys:
        group = group_of(key)
        held = tuple((column, name) for column, name in group.metrics if column in results.columns)
        curves = tuple((column, name) for column, name in group.curve_metrics if column in results.columns)
        found.append(Group(group.key, group.title, held, curves, group.dimension, group.switches))
    return found


COUNT_COLUMNS = {"3d_IDS", "3d_FRAG", "2d_IDSW", "2d_Frag", "3d_HZ_MISS", "3d_HZ_FAKE"}
"""Summed (not averaged) in the results tables."""
