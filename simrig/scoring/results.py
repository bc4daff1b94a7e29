"""What ``simrig score`` reports: the metrics per class, per camera and overall, and the errors by cause —
as a readable table and as JSON (one key per metric; NaN written as null)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from simrig.dataset.outputs import atomic_file, write_text_atomic
from simrig.scoring.attribution import IGNORED, errors_by_cause
from simrig.scoring.planner import PLANNER_METRICS

METRICS_3D = ("AMOTA", "AMOTP", "MOTAR", "MOTA", "MOTP", "RECALL", "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN",
              "ATVE", "TVE")
"""3D metrics, nuScenes style (MOTP, AMOTP [m]; ATVE, TVE [m/s])."""
METRICS_2D = ("HOTA", "DetA", "AssA", "LocA", "MOTA", "MOTP", "IDSW", "Frag", "MT", "PT", "ML", "IDF1", "IDP",
              "IDR", "CLR_TP", "CLR_FN", "CLR_FP")
"""2D metrics, TrackEval style (MOTP: mean IoU of matches)."""
INTERPOLATION_WORDS = {"devkit": "track gaps filled as nuscenes-devkit 1.2.0 does",
                       "corrected": "track gaps filled linearly", "none": "track gaps not filled"}
"""How the 3D heading of :meth:`ScoreReport.table` names each ``interpolation``
(:mod:`simrig.formats.nuscenes.interpolation`)."""
IGNORED_COLUMNS = ("boxes", "ignored", "range", "height", "visibility", "truncation", "source", "unevaluated",
                   "delivered")
"""Per camera: ground-truth boxes in view, how many are ignored, and by each rule (a box may break several;
``source``: a distractor and ``unevaluated``: not evaluated, as an imported dataset's source marks it);
``delivered``: the scored (not ignored) boxes the camera's detector reported."""
COUNT_METRICS = {"LANE", "HZ_MISS", "HZ_FAKE", "IDS", "FRAG", "MT", "ML", "TP", "FP", "FN", "IDSW", "Frag", "PT",
                 "CLR_TP", "CLR_FN", "CLR_FP"}


@dataclass
class ScoreReport:
    """Scores of one tracker output on one dataset.

    metrics3d: ``{"overall": {...}, "per_class": {class: {...}}}`` or ``None`` (no 3D tracks, or a dataset
    with 2D ground truth only). metrics2d (``None`` on a dataset without cameras): ``{"overall": ...,
    "per_class": ..., "per_camera": ...}``, ``ground_truth`` (``overall`` and
    ``per_camera``: boxes in view, ignored, ignored by each rule, and ``delivered``: scored boxes the detector
    reported) and ``source`` (``tracks2d`` or
    ``projected 3D tracks``). errors: one row per error (:data:`~simrig.scoring.attribution.ERRORS_SCHEMA`).
    metrics3d's ``overall`` also holds the planner-aware scores (:data:`~simrig.scoring.planner.PLANNER_METRICS`)
    and ``planner`` says whether they were scored; plan: the ego's plan per frame on the ground truth and on the
    tracks (:data:`~simrig.scoring.planner.PLAN_SCHEMA`; None when not scored).
    """

    dataset: str
    tracks: str
    scenario: str
    seed: int
    metrics3d: dict | None
    metrics2d: dict | None
    errors: pa.Table
    settings: dict = field(default_factory=dict)
    plan: pa.Table | None = None

    def to_dict(self) -> dict:
        """JSON-ready: metric values with NaN as None."""
        return _clean({
            "dataset": self.dataset, "tracks": self.tracks, "scenario": self.scenario, "seed": self.seed,
            "settings": self.settings, "3d": self.metrics3d, "2d": self.metrics2d,
            "errors_by_cause": errors_by_cause(self.errors),
        })

    def write_json(self, path: Path | str) -> None:
        write_text_atomic(Path(path), json.dumps(self.to_dict(), indent=2) + "\n")

    def write_errors(self, path: Path | str) -> None:
        """Every error with its causes, as Parquet (written atomically: the old file or the new one)."""
        with atomic_file(Path(path)) as temporary:
            pq.write_table(self.errors, temporary)

    def write_plan(self, path: Path | str) -> None:
        """The ego's plan per frame on the ground truth and on the tracks, as Parquet (atomically)."""
        with atomic_file(Path(path)) as temporary:
            pq.write_table(self.plan, temporary)

    def table(self) -> str:
        """The readable summary ``simrig score`` prints."""
        lines = [f"dataset   {self.dataset} ({self.scenario}, seed {self.seed})", f"tracks    {self.tracks}"]
        if self.metrics3d is not None:
            filled = INTERPOLATION_WORDS.get(self.settings.get("interpolation", "none"), "")
            lines += ["", "3D (BEV centre distance < 2 m; class ranges 50 m, motorcycle, pedestrian, bicycle 40 m; "
                          f"{filled})"]
            lines += _grid(METRICS_3D, {"overall": self.metrics3d["overall"], **self.metrics3d["per_class"]})
            lines += ["", *_planner_lines(self.metrics3d)]
        elif self.settings.get("ground_truth") == "2d only":
            lines += ["", "3D: not scored (the dataset's ground truth is 2D only)"]
        if self.metrics3d is None and self.metrics2d is not None and self.metrics2d.get("source") == "tracks2d":
            lines += ["", "Planner-aware: not scored (2D tracks: the ego's planner needs 3D tracks)"]
        if self.metrics2d is None:
            lines += ["", "2D: not scored (the dataset has no cameras)"]
            return "\n".join(lines + _error_lines(self.errors))
        lines += ["", f"2D per camera (IoU; {self.metrics2d['source']})"]
        rows = {"overall": self.metrics2d["overall"], **self.metrics2d["per_camera"],
                **{f"class {name}": value for name, value in self.metrics2d["per_class"].items()}}
        lines += _grid(METRICS_2D, rows)
        truth = self.metrics2d.get("ground_truth")
        if truth is not None:
            lines += ["", "2D ground truth: boxes in view; ignored, and by which rule (not scored: "
                      f"{_evaluation_text(self.settings.get('evaluation'))}); delivered: scored boxes the "
                      "detector reported"]
            lines += _grid(IGNORED_COLUMNS, {"overall": truth["overall"], **truth["per_camera"]})
        return "\n".join(lines + _error_lines(self.errors))


def _planner_lines(metrics3d: dict) -> list[str]:
    """The planner-aware block of the readable summary (:mod:`simrig.scoring.planner`)."""
    planner = metrics3d.get("planner", {})
    if not planner.get("scored"):
        return [f"Planner-aware: {planner.get('note', 'not scored')}"]
    return ["Planner-aware, open loop (the ego's IDM/MOBIL on the ground truth vs on the tracks; PKL [nats/frame], "
            "dACC [m/s²], LANE, HZ_MISS, HZ_FAKE [frames])",
            *_grid(PLANNER_METRICS, {"overall": metrics3d["overall"]})]


def _error_lines(errors: pa.Table) -> list[str]:
    """The errors-by-cause tables of the readable summary."""
    lines = []
    for dimension, table in errors_by_cause(errors).items():
        lines += ["", f"{dimension.upper()} errors by cause (an error with several causes counts in each)"]
        lines.append(f"  {'cause':<22}{'FN':>8}{'IDS':>8}{'FRAG':>8}")
        for cause, counts in table.items():
            if cause == IGNORED:
                lines.append(f"  {'ignored (not errors)':<22}{counts['FN']:>8}{'-':>8}{'-':>8}")
                continue
            lines.append(f"  {cause:<22}{counts['FN']:>8}{counts['IDS']:>8}{counts['FRAG']:>8}")
    return lines


def _evaluation_text(config: dict | None) -> str:
    """The evaluation settings in a few words."""
    if not config:
        return "settings not recorded"
    if not config["ignore"]:
        return "nothing, ignore = false"
    ranges = config["range_m"]
    range_text = (f"{ranges:g} m" if not isinstance(ranges, dict)
                  else ", ".join(f"{name} {value:g} m" for name, value in ranges.items()))
    return (f"range {range_text}; height < {config['min_height_px']:g} px; visible fraction ≤ "
            f"{config['min_visible_fraction']:g}; truncation > {config['max_truncation']:g}")


def _format(name: str, value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if name in COUNT_METRICS or name in IGNORED_COLUMNS:
        return str(int(value))
    return f"{value:.3f}"


def _grid(names: tuple[str, ...], rows: dict[str, dict]) -> list[str]:
    width = max(len(label) for label in rows) + 2
    cells = [[_format(name, values.get(name)) for name in names] for values in rows.values()]
    widths = [max(len(name), *(len(row[i]) for row in cells)) + 2 for i, name in enumerate(names)]
    out = ["  " + " " * width + "".join(name.rjust(w) for name, w in zip(names, widths, strict=True))]
    for label, row in zip(rows, cells, strict=True):
        out.append("  " + label.ljust(width) + "".join(cell.rjust(w) for cell, w in zip(row, widths, strict=True)))
    return out


def _clean(value):
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, float) and math.isnan(value):
        return None
    if hasattr(value, "item"):
        return _clean(value.item())
    return value
