"""The report's tables: results per tracker, per scenario, and errors by cause."""

from __future__ import annotations

import pandas as pd

from ..markdown import number, table
from ..scoring.attribution import ATTRIBUTION_CAUSES, IGNORED
from .groups import COUNT_COLUMNS, Group
from .load import BenchResults
from .paired import paired_difference


def _base_rows(bench: BenchResults) -> pd.DataFrame:
    """The points at each scenario's own settings (the sweeps' values equal to them included once)."""
    return bench.results[bench.results["sweep"] == ""]


def tracker_table(bench: BenchResults, group: Group) -> list[str]:
    """Rows: trackers of ``group``; columns: its metrics over the base points (mean over scenarios and seeds;
    counts summed)."""
    rows = _base_rows(bench)
    rows = rows[rows["scored"] == group.key]
    out = []
    for tracker, frame in rows.groupby("tracker", sort=False):
        cells = [f"`{tracker}`", str(frame["scenario"].nunique()), str(len(frame))]
        for column, _ in group.metrics:
            values = frame[column]
            cells.append(number(values.sum() if column in COUNT_COLUMNS else values.mean()))
        out.append(cells)
    header = ["tracker", "scenarios", "sequences"] + [
        f"{name} (sum)" if column in COUNT_COLUMNS else name for column, name in group.metrics]
    return table(header, out)


def paired_table(bench: BenchResults, group: Group) -> list[str]:
    """Rows: every tracker of ``group`` but the first; cells: its paired difference from the first tracker in each
    of the group's curve metrics, over the (scenario, seed) sequences both ran at the base points — the mean
    difference per sequence with its 95 % interval (:mod:`.paired`). Empty with fewer than two trackers."""
    rows = _base_rows(bench)
    rows = rows[rows["scored"] == group.key]
    trackers = list(dict.fromkeys(rows["tracker"]))
    if len(trackers) < 2:
        return []
    columns = [column for column, _ in group.curve_metrics]
    per_sequence = rows.groupby(["tracker", "scenario", "seed"], sort=False)[columns].mean()
    reference = per_sequence.loc[trackers[0]]
    out = []
    for tracker in trackers[1:]:
        mine = per_sequence.loc[tracker]
        both = reference.index.intersection(mine.index)
        cells = [f"`{tracker}`", str(len(both))]
        for column in columns:
            difference = paired_difference(mine.loc[both, column].to_numpy(), reference.loc[both, column].to_numpy())
            cells.append(difference.text(digits=1 if column in COUNT_COLUMNS else 3))
        out.append(cells)
    return table(["tracker", "sequences"] + [f"Δ {name}" for _, name in group.curve_metrics], out)


def drive_table(bench: BenchResults, group: Group) -> list[str]:
    """Rows: trackers of ``group``; cells: drives with a collision, drives with a near miss, the median least time
    to collision [s], hard brakes per drive, and the progress lost to the ground-truth drive [m] per drive."""
    rows = _base_rows(bench)
    rows = rows[rows["scored"] == group.key]
    out = []
    for tracker, frame in rows.groupby("tracker", sort=False):
        out.append([f"`{tracker}`", str(len(frame)), f"{int((frame['drive_collision'] > 0).sum())}",
                    f"{int((frame['drive_near_misses'] > 0).sum())}", number(frame["drive_min_ttc_s"].median()),
                    number(frame["drive_hard_brakes"].mean()), number(frame["drive_progress_lost_m"].mean())])
    return table(["tracker", "drives", "with a collision", "with a near miss", "median least TTC [s]",
                  "hard brakes per drive", "progress lost [m]"], out)


def ranking_note(bench: BenchResults, group: Group) -> list[str]:
    """For 3D trackers with planner-aware scores: the trackers ordered by HOTA, by AMOTA and by PKL (lower is
    better), and a note where PKL's order disagrees with a classic one (Spearman's ρ of the means below 1)."""
    rows = _base_rows(bench)
    rows = rows[rows["scored"] == group.key]
    if "3d_PKL" not in rows.columns or rows["3d_PKL"].isna().all() or rows["tracker"].nunique() < 2:
        return []
    means = rows.groupby("tracker", sort=False)[["2d_HOTA", "3d_AMOTA", "3d_PKL"]].mean()
    orders = {"HOTA": means["2d_HOTA"].sort_values(ascending=False).index,
              "AMOTA": means["3d_AMOTA"].sort_values(ascending=False).index,
              "PKL": means["3d_PKL"].sort_values().index}
    lines = ["Ranked by the means above (best first):", ""]
    lines += [f"- {name}: " + " > ".join(f"`{t}`" for t in order) for name, order in orders.items()]
    disagree = []
    for name, column in (("HOTA", "2d_HOTA"), ("AMOTA", "3d_AMOTA")):
        rho = means[column].rank().corr(-means["3d_PKL"].rank())  # Spearman's ρ: Pearson's on the ranks
        if rho < 1 - 1e-9:
            disagree.append(f"{name} (Spearman's ρ {rho:+.2f})")
    lines += ["", (f"The planner-aware order disagrees with {' and '.join(disagree)}: the errors these trackers make "
                   "differ in what they would change for the ego (docs/planner.md)." if disagree else
                   "The planner-aware order agrees with HOTA's and AMOTA's."), ""]
    return lines


def scenario_table(bench: BenchResults, group: Group) -> list[str]:
    """Rows: scenarios; columns: trackers of ``group``; cells: HOTA (mean over seeds) and identity switches
    (summed over seeds)."""
    rows = _base_rows(bench)
    rows = rows[rows["scored"] == group.key]
    trackers = list(dict.fromkeys(rows["tracker"]))
    out = []
    for scenario, frame in rows.groupby("scenario", sort=False):
        cells = [f"`{scenario}`"]
        for tracker in trackers:
            mine = frame[frame["tracker"] == tracker]
            cells.append("-" if mine.empty else
                         f"{number(mine['2d_HOTA'].mean())} ({number(mine[group.switches].sum())})")
        out.append(cells)
    return table(["scenario"] + [f"`{t}`" for t in trackers], out)


def causes_table(bench: BenchResults, group: Group, kind: str) -> list[str]:
    """Rows: trackers of ``group``; columns: causes; cells: how many errors of ``kind`` (IDS or FN) carry the
    cause, over every cell of the suite (an error with two causes counts under both; ``total`` once)."""
    causes = bench.unique_cells(bench.causes)
    causes = causes[(causes["scored"] == group.key) & (causes["dimension"] == group.dimension)
                    & (causes["kind"] == kind)]
    trackers = list(dict.fromkeys(bench.results.loc[bench.results["scored"] == group.key, "tracker"]))
    present = [cause for cause in (*ATTRIBUTION_CAUSES, "total", IGNORED) if cause in set(causes["cause"])]
    counts = causes.groupby(["tracker", "cause"])["count"].sum()
    out = [[f"`{tracker}`"] + [int(counts.get((tracker, cause), 0)) for cause in present] for tracker in trackers]
    return table(["tracker"] + present, out)


def camera_table(bench: BenchResults, group: Group) -> list[str]:
    """Rows: trackers of ``group``; columns: cameras; cells: 2D HOTA (mean over the base points) and IDSW
    (summed), ``-`` where nothing was scored (no box on either side); a last row with the ground-truth boxes in
    view and those ignored. Empty without camera data."""
    cameras = bench.cameras
    if cameras is None or cameras.empty:
        return []
    rows = cameras[(cameras["sweep"] == "") & (cameras["scored"] == group.key)]
    if rows.empty:
        return []
    names = list(dict.fromkeys(rows["camera"]))
    out = []
    for tracker, frame in rows.groupby("tracker", sort=False):
        by_camera = frame.groupby("camera", sort=False)
        hota, switches = by_camera["HOTA"].mean(), by_camera["IDSW"].sum()
        scored = by_camera["CLR_TP"].sum() + by_camera["CLR_FN"].sum() + by_camera["CLR_FP"].sum()
        out.append([f"`{tracker}`"] + [f"{number(hota[name])} ({number(switches[name])})"
                                       if name in hota and scored[name] > 0 else "-" for name in names])
    first = rows[rows["tracker"] == rows["tracker"].iloc[0]].groupby("camera", sort=False)
    boxes, ignored = first["boxes"].sum(), first["ignored"].sum()
    out.append(["ground truth (ignored)"] + [f"{number(boxes[name])} ({number(ignored[name])})" for name in names])
    return table(["tracker"] + [f"`{name}`" for name in names], out)
