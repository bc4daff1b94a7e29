"""``score``: a tracker's output against a dataset, every metric and every error's causes in one report."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from simrig.dataset.tracks_file import TrackSet
from simrig.formats.evaluation import evaluation_of, ignore_rules, ignored_counts, projected_in_range
from simrig.formats.nuscenes.interpolation import INTERPOLATIONS
from simrig.formats.nuscenes.samples import sample_tokens, scene_of_frame
from simrig.formats.tracks import read_tracks_as
from simrig.scenarios.evaluation_schema import EvaluationConfig
from simrig.scoring.results import METRICS_2D, METRICS_3D, ScoreReport

from ..dataset import Dataset
from ..dataset.ground_truth import GroundTruth, relative_to_true_ego
from ..errors import TracksError
from .amota import amota_family, combine_classes
from .attribution import ERRORS_SCHEMA, Attributor
from .bev import BevSequence
from .clear import CLEAR, ClearEvents
from .clear3d import Accumulation, fragmentations
from .counts import combine
from .hota import HOTA
from .identity import Identity
from .inputs import camera_sequences, class_sequences
from .planner import PLANNER_METRICS, planner_road_of, planner_scores
from .truth_plans import truth_side_of

LOOKBACK_S = 1.0
"""[s] an identity switch is also tagged with the causes of this long before it (see attribution)."""
_CLEAR = CLEAR()
UNITS_2D = (HOTA(), _CLEAR, Identity())
"""The 2D metric units; their values are combined by name (:func:`~simrig.scoring.counts.combine`)."""


def score(dataset: Dataset | Path | str, tracks: TrackSet | Path | str, *, lookback_s: float = LOOKBACK_S,
          camera: str | None = None, truth: GroundTruth | None = None,
          evaluation: EvaluationConfig | dict | None = None, fmt: str | None = None,
          interpolation: str = "devkit", planner: bool = True) -> ScoreReport:
    """Score ``tracks`` (a tracks folder or file, or a read :class:`TrackSet`) against ``dataset``.

    ``fmt``: the tracks' format — ``simrig``, ``motchallenge``, ``kitti`` or ``nuscenes``
    (:mod:`simrig.formats.tracks`); detected from the path when ``None``.

    In 2D a 3D tracker's boxes are projected into the cameras, those beyond their class range dropped first as
    the devkit drops far predictions (:func:`~simrig.formats.evaluation.projected_in_range`). With ``camera``,
    only that camera is scored, in 2D (a 2D tracker's own boxes there, or a 3D tracker's projected into it)
    against the actors in its view, and the 3D metrics are left out: how a per-camera tracker and one that uses
    the other cameras compare on one camera's ground truth.

    ``truth``: the dataset's ground truth when the caller already holds it (scoring several trackers on one
    dataset reads it once; by default it is read once per :class:`Dataset` object). ``evaluation``: which 2D
    ground truth is ignored — an :class:`EvaluationConfig`, or a dict of keys put on top of the dataset
    scenario's ``[evaluation]`` table (:mod:`simrig.scenarios.evaluation_schema`). ``interpolation``: how the
    gaps inside 3D tracks are filled before the AMOTA family — ``devkit`` (the default: the nuScenes devkit
    1.2.0 as shipped, so the numbers compare with published ones), ``corrected`` or ``none``
    (:mod:`simrig.formats.nuscenes.interpolation`).

    ``planner``: also ask the ego's planner (:mod:`simrig.scoring.planner`; the planner-aware scores, each miss's
    consequence and the per-frame plans). False leaves them NaN ("not asked"), for callers that need none of them
    (``simrig explain`` on other metrics: dozens of counterfactual runs).
    """
    if interpolation not in INTERPOLATIONS:
        raise TracksError(f"--interpolation {interpolation!r}: choose one of {', '.join(INTERPOLATIONS)}")
    if not isinstance(dataset, Dataset):
        dataset = Dataset.open(dataset)
    if camera is not None and camera not in dataset.rig.camera_names:
        raise TracksError(f"--camera {camera!r}: the dataset's rig {dataset.rig.name!r} has cameras "
                          f"{', '.join(dataset.rig.camera_names)}")
    config = evaluation_of(dataset.scenario, evaluation)
    truth = dataset.ground_truth if truth is None else truth
    if not isinstance(tracks, TrackSet):
        tracks = read_tracks_as(tracks, fmt, frame_count=len(truth.frames), cameras=truth.rig.camera_names,
                                tokens=sample_tokens(dataset), classes=config.classes,
                                scenes=scene_of_frame(dataset))
    _check_made_on(dataset, tracks)
    if tracks.tracks3d is not None and truth.given_egos is not None:  # scored relative to the ego
        tracks = TrackSet(tracks.source, relative_to_true_ego(truth, tracks.tracks3d), tracks.tracks2d, tracks.made_on)
    has_2d_tracks = tracks.tracks2d is not None and len(tracks.tracks2d) > 0
    if not dataset.has_3d and not has_2d_tracks and tracks.tracks3d is not None and len(tracks.tracks3d):
        raise TracksError(f"{tracks.source}: 3D tracks, but dataset {str(dataset.path)!r} holds 2D ground truth "
                          "only (imported without a rig): score 2D tracks on it")
    if not dataset.has_2d and has_2d_tracks:
        raise TracksError(f"{tracks.source}: 2D tracks, but dataset {str(dataset.path)!r} has no cameras "
                          "(imported 3D ground truth only): score 3D tracks on it")
    lookback = int(round(lookback_s * float(dataset.scenario["frame_rate_hz"])))
    errors = []
    metrics3d = metrics2d = plan = None
    if tracks.tracks3d is not None and camera is None and dataset.has_3d:
        metrics3d, errors3d = _score_3d(truth, tracks, lookback, interpolation)
        if planner:
            errors3d, plan = _planner(metrics3d, errors3d, dataset, truth, tracks.tracks3d)
        else:
            _not_planned(metrics3d, "not asked")
        errors.append(errors3d)
    if dataset.has_2d:
        if has_2d_tracks:
            rows2d, source = tracks.tracks2d, "tracks2d"
        elif tracks.tracks3d is not None:
            rows2d, source = projected_in_range(truth, tracks.tracks3d, config), "projected 3D tracks"
        else:
            rows2d, source = tracks.tracks2d, "tracks2d"
        metrics2d, errors2d = _score_2d(truth, rows2d, lookback, camera, config)
        metrics2d["source"] = source
        errors.append(errors2d)
    ground_truth = {} if dataset.source is None else {
        "ground_truth": "2d only" if not dataset.has_3d else "3d only" if not dataset.has_2d else "2d and 3d"}
    return ScoreReport(
        dataset=str(dataset.path), tracks=tracks.source, scenario=dataset.scenario["name"], seed=dataset.seed,
        metrics3d=metrics3d, metrics2d=metrics2d,
        errors=pa.concat_tables(errors) if errors else ERRORS_SCHEMA.empty_table(), plan=plan,
        settings={"lookback_s": lookback_s, **({"camera": camera} if camera is not None else {}), **ground_truth,
                  "interpolation": interpolation,
                  "evaluation": config.model_dump(mode="json")},
    )


def _check_made_on(dataset: Dataset, tracks: TrackSet) -> None:
    """Tracks simrig made on one dataset are not scored on a dataset with other ground truth (another seed,
    scenario or rig): the numbers would be meaningless, not wrong-looking."""
    made_on = tracks.made_on
    if made_on is None or made_on.get("ground_truth_sha256") == dataset.identity["ground_truth_sha256"]:
        return
    raise TracksError(f"{tracks.source}: these tracks were made on a dataset of scenario "
                      f"{made_on.get('scenario')!r}, seed {made_on.get('seed')}, not on {str(dataset.path)!r} "
                      f"(scenario {dataset.scenario['name']!r}, seed {dataset.seed}; its ground truth differs): "
                      "score them on the dataset they were made on")


def _score_3d(truth: GroundTruth, tracks: TrackSet, lookback: int, interpolation: str) -> tuple[dict, pa.Table]:
    attributor = Attributor(truth, truth.miss_causes_3d, lookback)
    per_class, errors = {}, []
    for seq in class_sequences(truth, tracks.tracks3d, interpolation):
        result = amota_family(seq)
        per_class[seq.label] = {name: result.metrics[name] for name in METRICS_3D}
        if result.best is not None or seq.num_gt_dets:
            errors.append(attributor.tag(seq.label, "", "3d", _events_3d(seq, result.best)))
    overall = combine_classes(per_class, METRICS_3D)
    return {"overall": overall, "per_class": per_class}, _concat(errors)


def _not_planned(metrics3d: dict, note: str) -> None:
    """The planner-aware scores left NaN, with why under ``metrics3d["planner"]``."""
    metrics3d["overall"].update(dict.fromkeys(PLANNER_METRICS, float("nan")))
    metrics3d["planner"] = {"scored": False, "note": note}


def _planner(metrics3d: dict, errors3d: pa.Table, dataset: Dataset, truth: GroundTruth,
             tracks3d) -> tuple[pa.Table, pa.Table | None]:
    """Adds the planner-aware scores (:mod:`simrig.scoring.planner`) to ``metrics3d["overall"]`` (NaN, with a note
    under ``metrics3d["planner"]``, for a dataset simrig did not simulate) and each 3D miss's consequence to the
    errors; returns the errors and the per-frame plan table (None when not scored)."""
    road = planner_road_of(dataset)
    if road is None:
        _not_planned(metrics3d, "not scored: the dataset was not simulated by simrig, so there is no ego planner "
                                "to ask")
        return errors3d, None
    kinds = errors3d.column("kind").to_numpy(zero_copy_only=False)
    frames = errors3d.column("frame").to_numpy()
    actors = errors3d.column("actor_id").to_numpy()
    misses = np.flatnonzero(kinds == "FN")
    truth_side = truth_side_of(dataset, road, truth, dataset.identity["ground_truth_sha256"])
    scores = planner_scores(road, truth, tracks3d, np.column_stack([frames[misses], actors[misses]]), truth_side)
    weight = errors3d.column("consequence").to_numpy(zero_copy_only=False).copy()
    weight[misses] = [scores.consequence.get((int(frames[i]), int(actors[i])), 0.0) for i in misses]
    metrics3d["overall"].update(scores.metrics)
    metrics3d["planner"] = {"scored": True}
    index = errors3d.schema.get_field_index("consequence")
    return errors3d.set_column(index, "consequence", pa.array(weight, pa.float64())), scores.frames


def _events_3d(seq: BevSequence, best: Accumulation | None) -> ClearEvents:
    """The misses, switches and fragmentations of an accumulation (everything missed when ``None``)."""
    matched = best.matched if best is not None else np.zeros(0, dtype=np.int64)
    tracked = np.zeros(seq.num_gt_dets, dtype=bool)
    tracked[seq.pair_gt[matched]] = True
    frames, actors, track_labels = seq.frames, seq.gt_labels, seq.tracker_labels
    missed = np.nonzero(~tracked)[0]
    switches = np.zeros((0, 5), dtype=np.int64)
    if best is not None and best.switch.any():
        s = matched[best.switch]
        switches = np.column_stack([
            frames[seq.pair_frame[s]], actors[seq.gt_id[seq.pair_gt[s]]],
            track_labels[seq.tracker_id[seq.pair_tracker[s]]],
            track_labels[best.previous_track[best.switch]], frames[best.previous_frame[best.switch]],
        ]).astype(np.int64)
    resumed, last = fragmentations(seq, tracked)
    return ClearEvents(
        misses=np.column_stack([frames[seq.gt_frame[missed]], actors[seq.gt_id[missed]]]).astype(np.int64),
        switches=switches,
        fragmentations=np.column_stack([
            frames[seq.gt_frame[resumed]], actors[seq.gt_id[resumed]], frames[seq.gt_frame[last]]
        ]).astype(np.int64).reshape(-1, 3),
    )


def _score_2d(truth: GroundTruth, rows2d, lookback: int, camera: str | None,
              config: EvaluationConfig) -> tuple[dict, pa.Table]:
    parts, errors = [], []
    cameras = truth.rig.camera_names
    scored = cameras if camera is None else (camera,)
    rules = ignore_rules(truth, config)
    for seq in camera_sequences(truth, rows2d, scored, ignored=rules if rules.any() else None,
                                classes=config.classes):
        counts = {}
        for unit in UNITS_2D:
            if unit is _CLEAR:  # the same pass also gives the events behind its errors
                counts[unit.name], events = _CLEAR.count_with_events(seq)
            else:
                counts[unit.name] = unit.count(seq)
        parts.append((seq.camera, seq.label, counts))
        c = cameras.index(seq.camera)
        attributor = Attributor(truth, truth.miss_causes(c), lookback)
        errors.append(attributor.tag(seq.label, seq.camera, "2d", events))
        if len(seq.ignored_misses):
            errors.append(attributor.tag_ignored(seq.label, seq.camera, seq.ignored_misses, rules[:, c]))

    def metrics(selected: list[dict]) -> dict:
        values = combine(UNITS_2D, selected)
        return {name: values[name] for name in METRICS_2D}

    columns = slice(None) if scored == cameras else [cameras.index(name) for name in scored]  # a view for all
    in_view, scored_rules = truth.in_view[:, columns], rules[:, columns]
    delivered = in_view & truth.detected[:, columns] & (scored_rules == 0)

    def accounting(i: slice | int) -> dict:
        return {"boxes": int(in_view[:, i].sum()), **ignored_counts(scored_rules[:, i]),
                "delivered": int(delivered[:, i].sum())}

    return {
        "overall": metrics([p for _, _, p in parts]),
        "per_camera": {name: metrics([p for cam, _, p in parts if cam == name]) for name in scored},
        "per_class": {label: metrics([p for _, lab, p in parts if lab == label])
                      for label in sorted({lab for _, lab, _ in parts})},
        "ground_truth": {"overall": accounting(slice(None)),
                         "per_camera": {name: accounting(i) for i, name in enumerate(scored)}},
    }, _concat(errors)


def _concat(tables: list[pa.Table]) -> pa.Table:
    return pa.concat_tables(tables) if tables else ERRORS_SCHEMA.empty_table()
