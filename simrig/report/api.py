"""``write_report``: ``reports/<suite>/index.md`` from a finished bench folder, with its PNGs beside it."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path

from ..benchmark.api import BENCH_FILE
from ..benchmark.results import CAMERAS, CAUSES, RESULTS
from ..dataset.outputs import atomic_file, check_output_path, check_own_folder, write_text_atomic
from ..explain.bench import EXPLAIN_TABLE
from ..markdown import table
from .cause_costs import cause_costs_section
from .curves import curve_table, plot_sweep, plot_sweep_by_scenario
from .groups import groups
from .load import BenchResults, load_bench
from .summary import (
    camera_table,
    causes_table,
    drive_table,
    paired_table,
    ranking_note,
    scenario_table,
    tracker_table,
)
from .validity_section import metric_validity_section
from .worst_cell import inspect_worst

DEFAULT_REPORT_DIR = "report"
"""The report's folder inside the bench folder when no ``out`` is given (never a folder of the working tree)."""


def write_report(results: Path | str, *, out: Path | str | None = None) -> Path:
    """Write the report of the bench folder ``results`` into ``out`` (default ``BENCH/report``): index.md,
    the figures, and copies of the results, causes and bench description it was made from (so that
    ``simrig report OUT`` makes it again). Returns the path of index.md."""
    bench = load_bench(results)
    out = Path(out) if out is not None else bench.folder / DEFAULT_REPORT_DIR
    check_output_path(out, what="--out")
    check_own_folder(out, what="report folder", marker=BENCH_FILE, marker_keys=("suite", "command", "cells"))
    out.mkdir(parents=True, exist_ok=True)
    for name in (RESULTS, CAUSES, CAMERAS, BENCH_FILE, EXPLAIN_TABLE):
        if (bench.folder / name).is_file() and (bench.folder / name).resolve() != (out / name).resolve():
            with atomic_file(out / name) as copy:
                shutil.copyfile(bench.folder / name, copy)
    lines = _header(bench, out)
    lines += _results_section(bench)
    lines += _failures_section(bench)
    lines += _curves_section(bench, out)
    lines += _causes_section(bench)
    lines += cause_costs_section(bench.folder, bench.suite, [entry["name"] for entry in bench.trackers])
    lines += _worst_section(bench, out)
    if bench.description["suite_settings"].get("closed_loop"):
        lines += metric_validity_section(bench, out)
    index = out / "index.md"
    write_text_atomic(index, "\n".join(lines) + "\n")
    return index


def _header(bench: BenchResults, out: Path) -> list[str]:
    settings = bench.description["suite_settings"]
    frame = bench.results
    return [
        f"# Bench report: `{bench.suite}`", "",
        settings.get("description", ""), "",
        f"Produced by `{bench.description['command']}` then `simrig report {bench.description['out']}"
        f"{'' if out == Path('reports') / bench.suite else f' --out {out}'}`. "
        f"{frame['scenario'].nunique()} scenario{'s' * (frame['scenario'].nunique() != 1)}, seeds "
        f"{', '.join(str(s) for s in settings['seeds'])}; {len(bench.description['cells'])} cells (distinct "
        f"datasets), {len(frame)} result rows (point × tracker). The tables here are `{RESULTS}` and `{CAUSES}` "
        "in this folder.", "",
        "Each scenario runs at its own settings (the *base* points) and, for each sweep, with one parameter "
        "changed. HOTA, AssA and IDF1 are TrackEval's 2D metrics; AMOTA, MOTA, IDS and FRAG nuScenes' 3D "
        "ones. A tracker scored on one camera is compared only with others scored there.", "",
    ]


def _results_section(bench: BenchResults) -> list[str]:
    lines = ["## Results per tracker", ""]
    if not (bench.results["sweep"] == "").any():
        return lines + ["The suite runs no scenario at its own settings (`base = false`): its results are the "
                        "robustness curves below.", ""]
    lines += ["At each scenario's own settings: metrics are means over scenarios and seeds, counts are sums.", ""]
    for group in groups(bench.results):
        lines += [f"### {group.title}", ""] + tracker_table(bench, group) + [""]
        paired = paired_table(bench, group)
        if paired:
            first = next(iter(dict.fromkeys(bench.results.loc[bench.results["scored"] == group.key, "tracker"])))
            lines += [f"Paired against `{first}` on the same sequences (scenario × seed): the mean per-sequence "
                      "difference (tracker − reference; IDS and IDSW per sequence) with its 95 % BCa bootstrap "
                      "interval over sequences; `n.s.`: the interval contains 0, so the suite cannot tell the two "
                      "apart.", ""] + paired + [""]
        lines += ranking_note(bench, group)
        if bench.description["suite_settings"].get("closed_loop"):
            lines += ["Closed loop: each tracker drove every cell; the outcomes against the cell's ground-truth "
                      "drive (docs/planner.md).", ""] + drive_table(bench, group) + [""]
        lines += ["Per scenario: HOTA, mean over seeds (identity switches, summed over seeds).", ""]
        lines += scenario_table(bench, group) + [""]
        per_camera = camera_table(bench, group)
        if per_camera:
            lines += ["Per camera: 2D HOTA, mean over scenarios and seeds (IDSW, summed; a 3D tracker's boxes "
                      "projected into the camera). Last row: ground-truth boxes in view, and how many of them "
                      "the evaluation region ignored, summed.", ""]
            lines += per_camera + [""]
    return lines


def _failures_section(bench: BenchResults) -> list[str]:
    """The rows without metrics and why (a timeout, a refused traffic crash); nothing when there are none."""
    if "failure" not in bench.results.columns:
        return []
    failed = bench.results[bench.results["failure"].notna() & (bench.results["failure"] != "")]
    if not len(failed):
        return []
    rows = [[row["tracker"], row["scenario"], str(row["seed"]), row["sweep"] or "-", row["failure"]]
            for _, row in failed.iterrows()]
    return (["## Rows without metrics", "", f"{len(failed)} of {len(bench.results)} rows have no metrics; the "
             "tables above leave them out.", ""] + table(["tracker", "scenario", "seed", "sweep", "why"], rows) + [""])


def _curves_section(bench: BenchResults, out: Path) -> list[str]:
    lines = ["## Robustness curves", ""]
    found = groups(bench.results)
    for parameter in bench.description["parameters"]:
        slug = parameter.replace(".", "_")
        lines += [f"### {parameter}", ""]
        figure = plot_sweep(bench, parameter, found, out / f"curves-{slug}.png")
        if figure is None:
            lines += ["No points.", ""]
            continue
        lines += [f"![metrics against {parameter}]({figure.name})", ""]
        for group in found:
            for metric, name in group.curve_metrics[:1] + group.curve_metrics[-1:]:
                numbers = curve_table(bench, parameter, group, metric, name)
                if numbers:
                    where = {"3d": "", "2d": " (2D trackers)"}.get(group.key, f" (camera {group.key})")
                    lines += [f"{name}{where}, mean over seeds of the mean over scenarios:", ""] + numbers + [""]
        by_scenario = plot_sweep_by_scenario(bench, parameter, out / f"curves-{slug}-by-scenario.png")
        if by_scenario is not None:
            lines += [f"![HOTA against {parameter} per scenario]({by_scenario.name})", ""]
    return lines


def _causes_section(bench: BenchResults) -> list[str]:
    lines = ["## Errors by cause", "",
             "Over every cell of the suite. An error with several causes counts under each; `total` counts it "
             "once. `none`: no cause found in the look-back window. `ignored` (FN only): ground-truth boxes the "
             "evaluation region ignored and nobody tracked — not errors, not in `total`.", ""]
    for group in groups(bench.results):
        where = {"3d": "3D", "2d": "2D trackers, every camera"}.get(group.key, f"2D, camera {group.key}")
        for kind, name in (("IDS", "Identity switches"), ("FN", "Missed boxes (FN)")):
            lines += [f"{name} by cause ({where}):", ""] + causes_table(bench, group, kind) + [""]
    return lines


def _worst_section(bench: BenchResults, out: Path) -> list[str]:
    if bench.description["suite_settings"].get("closed_loop"):
        row = bench.results.sort_values("drive_progress_lost_m", ascending=False).iloc[0]
        return ["## The worst cell", "",
                "A closed-loop bench's cells are drives, each tracker in its own world: the drive that lost most "
                f"progress against the ground-truth drive is `{row['tracker']}` on {row['scenario']}, seed "
                f"{row['seed']} ({row['drive_progress_lost_m']:.1f} m). See it with `simrig drive "
                f"{row['scenario']} --seed {row['seed']} --tracker {row['tracker']} --frames {row['frames']}`.", ""]
    worst = inspect_worst(bench, out)
    row = worst.row
    entry = bench.trackers[0]
    point = f"{row['sweep']} = {row['value']:g}" if row["sweep"] else "its own settings"
    lines = ["## Worst cell", "",
             f"The cell where `{entry['name']}` (the suite's first tracker) switches identities most: "
             f"`{row['scenario']}` with {point}, seed {row['seed']} (cell `{row['cell']}`), HOTA "
             f"{row['2d_HOTA']:.3f}. Its dataset is `{Path(bench.description['cache']) / row['cell']}` "
             f"(`simrig bench` makes it again if missing): `simrig track` it with `{_tracker_arguments(entry)}` "
             "and `simrig score` the tracks to see every error.", "",
             f"![bird's-eye view of the worst cell]({worst.bev.name})", "",
             f"Camera mosaic at frame {worst.mosaic_frame} (the first switch): solid boxes ground truth, dashed "
             "boxes detections, dotted boxes the tracker's (`T<id>`).", "",
             f"![camera mosaic of the worst cell]({worst.mosaic.name})", ""]
    if worst.switches:
        rows = [[str(number), str(s["frame"]), s["camera"] or "-", s["class"], str(s["actor_id"]),
                 f"{s['previous_track_id']} → {s['track_id']}", ", ".join(s["causes"]) or "none"]
                for number, s in enumerate(worst.switches, start=1)]
        lines += ["The switches, numbered as on the plot:", ""]
        lines += table(["#", "frame", "camera", "class", "actor", "track", "causes"], rows) + [""]
    return lines


def _tracker_arguments(entry: dict) -> str:
    """The ``simrig track`` arguments of a suite's tracker entry."""
    words = ["--tracker", entry["tracker"]]
    for key, value in (entry.get("params") or {}).items():
        words += ["--param", f"{key}={value}"]
    return shlex.join(words)
