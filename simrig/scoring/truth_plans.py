"""The ground-truth half of the open-loop planner scores (:mod:`simrig.scoring.planner`): what the ego's planner
commands on the ground truth at every frame, and what missing each vehicle it reads would change.

Both depend on the ground truth alone, not on any tracker, so ``simrig generate`` records them with the dataset (the
``truth_plans`` table, :data:`simrig.dataset.tables.TRUTH_PLANS`) and scoring a tracker then asks the planner once a
frame, on the tracks. A dataset without the table (generated before it was recorded) gets them computed here the
same way, kept in memory for the next tracker on the same ground truth.

Per frame, the planner is asked on the ground truth within each class's evaluation range of the true ego
(:func:`in_range`, as :func:`~simrig.scoring.inputs.in_class_range` keeps rows), then once more without each vehicle
a neighbour search returned (:attr:`~simrig.world.ego_planner.EgoPlan.read`): the consequence of missing it is the
divergence between the two plans [nats]. Two shortcuts, both exact (the recorded table equals the plain computation
bit for bit, ``tests/test_planner.py``):

* a query without a vehicle reuses every neighbour-search answer that did not hold it (the nearest vehicle in front
  and behind is unchanged when another is removed);
* with the ego's ``POLITENESS`` at 0 (simrig's), a vehicle read only as the follower in the ego's own lane weighs 0
  without a query: MOBIL reads it only in the politeness term (it is the old follower), and IDM never reads a
  follower.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from simrig.dataset import Dataset
from simrig.dataset.ground_truth import GroundTruth
from simrig.errors import DatasetError
from simrig.types import EgoPose

from .inputs import class_ranges
from .planner import PlanningRoad, TruthSide, divergence


def in_range(ego: EgoPose, labels: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Which of one frame's actors (class names ``(n,)``, world boxes ``(n, ≥2)``) lie within their class's
    evaluation range of ``ego``: the same arithmetic as :func:`~simrig.scoring.inputs.in_class_range`."""
    return np.hypot(boxes[:, 0] - ego.x, boxes[:, 1] - ego.y) < class_ranges(labels)


class TruthPlanner:
    """Asks the ego's planner about one frame of ground truth at a time (module docstring)."""

    def __init__(self, road: PlanningRoad):
        self.road = road

    def frame(self, pose: EgoPose, actor_ids: np.ndarray, labels: np.ndarray, boxes: np.ndarray):
        """The planning ego at ``pose``, its plan on the actors in range, and the consequence [nats] of missing each
        actor the plan reads, by actor id."""
        keep = in_range(pose, labels, boxes)
        road = self.road
        ego = road.ego(pose)
        seen = road.phantoms(boxes[keep], actor_ids[keep])
        on_truth = road.plan_on(ego, seen)
        consequence = {}
        for actor in sorted(on_truth.read):
            holding = [lane for lane, found in on_truth.searches.items() if actor in _idents(found)]
            ego_lane_follower = holding == [on_truth.lane] and _idents(on_truth.searches[on_truth.lane][1:]) == [actor]
            if ego.POLITENESS == 0 and ego_lane_follower:
                consequence[actor] = 0.0  # the ego lane's follower only: read by the politeness term alone
                continue
            known = {lane: found for lane, found in on_truth.searches.items() if lane not in holding}
            without = road.plan_on(ego, [phantom for phantom in seen if phantom.ident != actor], known)
            consequence[actor] = float(divergence(on_truth.acceleration, on_truth.lane_change,
                                                  without.acceleration, without.lane_change))
        return ego, on_truth, consequence

    def row(self, frame: int, pose: EgoPose, actor_ids: np.ndarray, labels: np.ndarray,
            boxes: np.ndarray) -> dict[str, np.ndarray | pa.Array]:
        """One frame's ``truth_plans`` row, as column chunks for :class:`~simrig.dataset.DatasetWriter`."""
        _, plan, consequence = self.frame(pose, actor_ids, labels, boxes)
        actors = sorted(consequence)
        return {
            "frame": np.array([frame], np.int32), "acceleration": np.array([plan.acceleration]),
            "lane_change": np.array([plan.lane_change], np.int8), "leader": np.array([plan.leader], np.int64),
            "read": pa.array([actors], pa.list_(pa.int64())),
            "consequence": pa.array([[consequence[actor] for actor in actors]], pa.list_(pa.float64())),
        }


def _idents(found: tuple) -> list[int]:
    """The idents of a neighbour search's answer (phantoms; a road object has −1)."""
    return [int(getattr(v, "ident", -1)) for v in found if v is not None]


def computed_truth_side(road: PlanningRoad, truth: GroundTruth) -> TruthSide:
    """The ground-truth plans of every frame of ``truth``, computed now."""
    planner = TruthPlanner(road)
    f = len(truth.frames)
    acceleration, lane_change, leader = np.zeros(f), np.zeros(f, np.int8), np.full(f, -1, np.int64)
    consequence: dict[tuple[int, int], float] = {}
    egos = []
    for position, frame in enumerate(truth.frames.tolist()):
        rows = truth.frame_rows(position)
        ego, plan, weights = planner.frame(truth.egos[position], truth.actor_id[rows], truth.label[rows],
                                           truth.boxes[rows])
        egos.append(ego)
        acceleration[position], lane_change[position], leader[position] = (plan.acceleration, plan.lane_change,
                                                                           plan.leader)
        consequence.update({(frame, actor): weight for actor, weight in weights.items()})
    return TruthSide(acceleration, lane_change, leader, consequence, egos)


def recorded_truth_side(dataset: Dataset, truth: GroundTruth) -> TruthSide | None:
    """The ground-truth plans ``dataset`` recorded (its ``truth_plans`` table), or None when it has none; a table
    that does not hold one row per frame of the ground truth, in order, is a :class:`~simrig.errors.DatasetError`."""
    if not dataset.has_table("truth_plans"):
        return None
    table = dataset.table("truth_plans")
    frames = table.column("frame").to_numpy()
    if not np.array_equal(frames, truth.frames):
        raise DatasetError(f"dataset {str(dataset.path)!r}: truth_plans does not hold one row per frame of the "
                           f"ground truth ({len(frames)} rows for {len(truth.frames)} frames)")
    read, weights = table.column("read").combine_chunks(), table.column("consequence").combine_chunks()
    if not np.array_equal(read.value_lengths().to_numpy(zero_copy_only=False),
                          weights.value_lengths().to_numpy(zero_copy_only=False)):
        raise DatasetError(f"dataset {str(dataset.path)!r}: truth_plans read and consequence differ in length")
    row_frames = np.repeat(frames, read.value_lengths().to_numpy(zero_copy_only=False))
    consequence = dict(zip(zip(row_frames.tolist(), read.flatten().to_numpy().tolist(), strict=True),
                           weights.flatten().to_numpy().tolist(), strict=True))
    return TruthSide(table.column("acceleration").to_numpy(), table.column("lane_change").to_numpy(),
                     table.column("leader").to_numpy(), consequence)


_remembered: tuple[str | None, TruthSide | None] = (None, None)


def truth_side_of(dataset: Dataset, road: PlanningRoad, truth: GroundTruth, key: str | None = None) -> TruthSide:
    """The ground-truth plans of ``dataset``: recorded, or computed (module docstring). ``key`` names the ground
    truth (its SHA-256): computed plans are kept for the next call with the same key (the other trackers on the same
    dataset, ``simrig explain``'s counterfactuals of one world); never kept without a key."""
    global _remembered
    recorded = recorded_truth_side(dataset, truth)
    if recorded is not None:
        return recorded
    if key is not None and _remembered[0] == key:
        return _remembered[1]
    computed = computed_truth_side(road, truth)
    if key is not None:
        _remembered = (key, computed)
    return computed


__all__ = ["TruthPlanner", "computed_truth_side", "in_range", "recorded_truth_side", "truth_side_of"]
