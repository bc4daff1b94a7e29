"""Planner-aware scores (open loop): does a tracking error change what the car would do?

At every frame the ego's own planner (highway-env's IDM + MOBIL, :mod:`simrig.world.ego_planner`) is asked twice
from the ego's true pose: once on the ground truth, once on the tracker's 3D tracks, each as
:mod:`~simrig.world.phantoms` (position, velocity, size). Both sides keep what the 3D scores keep: boxes within their
class's evaluation range of the ego (:func:`~simrig.scoring.inputs.in_class_range`, 50 m for cars), so the
ground-truth planner sees what a perfect perception of that range would give it. MOBIL decides at every frame
(its 1 s timer is ignored), so every frame has a lane decision to compare. A frame without tracks (a dropped sensor
frame) is planned on an empty road, as the 3D scores count its ground truth missed.

Per frame: the commanded acceleration on each side [m/s²], the lane decision (−1 left, 0 keep, +1 right), the
vehicle each reacts to, and the divergence between the two plans. Over the run (:data:`PLANNER_METRICS`):

* ``PKL`` [nats per frame]: the mean per-frame Kullback–Leibler divergence KL(π_truth ‖ π_tracks) between the
  planner's action distributions, after "Learning to Evaluate Perception Models Using Planner-Centric Metrics"
  (Philion, Kar, Fidler, CVPR 2020), whose PKL is KL(planner | ground truth ‖ planner | detections) averaged over
  samples. Their planner is learned and outputs a distribution over future positions; ours is rule-based and
  deterministic, so the distribution is stated here as an **action noise model**: the executed acceleration is
  Gaussian around the command with σ = :data:`ACTION_NOISE_MPS2`, and the lane action is the decided one with
  probability 1 − :data:`LANE_SLIP`, each of the two others with :data:`LANE_SLIP` / 2. Then
  KL = Δa² / (2σ²) + [lane decisions differ] · (1 − 1.5 ε) · ln(2 (1 − ε) / ε) (3.36 nats at ε = 0.05, the same as
  Δa = 2.6 m/s²). Unlike the paper's, this divergence is over one step's action, not 4 s of future positions.
* ``dACC`` [m/s²]: mean |a_tracks − a_truth|.
* ``LANE``: frames whose lane decisions differ.
* ``HZ_MISS``: frames with a **missed hazard** — the ground-truth plan brakes (commands −:data:`HAZARD_MPS2` or
  less) and the track-fed plan commands at least :data:`HAZARD_MPS2` more (it brakes much less, or not at all).
* ``HZ_FAKE``: frames with an **invented hazard** — the track-fed plan brakes (−:data:`HAZARD_MPS2` or less) and
  the ground-truth plan commands at least :data:`HAZARD_MPS2` more (the tracks show a vehicle that is not there, or
  nearer or slower than it is).

**Consequence of each error.** A missed vehicle (a 3D FN at a frame) weighs the divergence between the plan on the
ground truth and the plan on the ground truth without that vehicle: what missing it alone would change. A vehicle
the ground-truth plan does not read (not the leader or follower in the ego's lane or a side lane) weighs exactly 0,
since removing it leaves every neighbour search, and so the plan, unchanged. Identity switches and fragmentations
are not weighed (NaN): the planner keeps no memory of identities, so an identity error changes its plan only through
the box it leaves behind, which the frame's divergence already counts.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from simrig.dataset import Dataset
from simrig.dataset.ground_truth import GroundTruth
from simrig.dataset.tracks_file import TrackRows
from simrig.seeding import RandomStreams, stream_generator

from .inputs import in_class_range

if TYPE_CHECKING:
    from simrig.scenarios.schema import TrafficConfig
    from simrig.world.ego_planner import EgoPlan

ACTION_NOISE_MPS2 = 1.0
"""[m/s²] σ of the executed acceleration around the planner's command (the action noise model of ``PKL``)."""
LANE_SLIP = 0.05
"""[-] probability that the lane action is not the decided one (shared by the two others; the ``PKL`` model)."""
HAZARD_MPS2 = 2.0
"""[m/s²] a hazard is braking at least this hard on one side that the other side's command is at least this much
above: the braking MOBIL refuses to impose on another driver (``LANE_CHANGE_MAX_BRAKING_IMPOSED``), the
deceleration highway-env's own planner treats as significant. (Counting any 1 m/s² shortfall below IDM's free-road
command flagged most frames of ordinary close following, where IDM is most sensitive to a metre or a metre per
second of tracking error.)"""
PLANNER_METRICS = ("PKL", "dACC", "LANE", "HZ_MISS", "HZ_FAKE")
"""The run's planner-aware scores (module docstring)."""
PLAN_SCHEMA = pa.schema([
    pa.field("frame", pa.int32()), pa.field("acceleration_truth", pa.float64()),
    pa.field("acceleration_tracks", pa.float64()), pa.field("lane_change_truth", pa.int8()),
    pa.field("lane_change_tracks", pa.int8()), pa.field("leader_truth", pa.int64()),
    pa.field("leader_tracks", pa.int64()), pa.field("divergence", pa.float64()), pa.field("hazard", pa.string()),
])
"""One row per frame: each side's command [m/s²] and lane decision, the actor id the ground-truth plan follows and
the track id the track-fed plan follows (−1: free road), their divergence [nats] and ``hazard`` (``missed``,
``invented`` or empty)."""
_LANE_DIVERGENCE = (1.0 - 1.5 * LANE_SLIP) * np.log(2.0 * (1.0 - LANE_SLIP) / LANE_SLIP)


def divergence(acceleration_p: np.ndarray, lane_p: np.ndarray, acceleration_q: np.ndarray,
               lane_q: np.ndarray) -> np.ndarray:
    """KL(π_p ‖ π_q) [nats] of the action noise model (module docstring) for plans p and q given as commanded
    accelerations [m/s²] and lane decisions (−1, 0, +1); broadcasts.

    >>> float(divergence(np.array(1.0), np.array(0), np.array(0.0), np.array(0)))
    0.5
    >>> round(float(divergence(np.array(0.0), np.array(-1), np.array(0.0), np.array(0))), 3)
    3.365
    """
    gaussian = (np.asarray(acceleration_p) - np.asarray(acceleration_q)) ** 2 / (2.0 * ACTION_NOISE_MPS2**2)
    return gaussian + _LANE_DIVERGENCE * (np.asarray(lane_p) != np.asarray(lane_q))


@dataclass(frozen=True)
class PlannerScores:
    """The open-loop planner-aware scores of one run: ``metrics`` (:data:`PLANNER_METRICS`), ``frames``
    (:data:`PLAN_SCHEMA`) and ``consequence``: the weight [nats] of each missed (frame, actor id) pair the
    ground-truth plan reads (every other miss weighs 0)."""

    metrics: dict[str, float]
    frames: pa.Table
    consequence: dict[tuple[int, int], float]


@dataclass(frozen=True)
class TruthSide:
    """The ground-truth half of the comparison (:mod:`simrig.scoring.truth_plans`), by frame position: the command
    [m/s²] ``(F,)``, the lane decision ``(F,)`` and the actor followed ``(F,)`` of the plan on the ground truth, the
    consequence [nats] of missing each vehicle it reads by (frame, actor id) (every other miss weighs 0), and the
    planning egos when they were built in this process (None: rebuilt from the true poses)."""

    acceleration: np.ndarray
    lane_change: np.ndarray
    leader: np.ndarray
    consequence: dict[tuple[int, int], float]
    egos: list | None = None


class PlanningRoad:
    """The road of a simrig-generated dataset, empty, and the ego's planner on it: the scenario's traffic settings
    and seed give highway-env's road and the ego's initial route, without simulating any traffic."""

    def __init__(self, traffic: TrafficConfig, frame_rate_hz: float, seed: int):
        # highway-env is imported here, not with simrig.scoring: scoring a 2D tracker or an imported dataset never
        # needs it, and importing it costs about 1.5 s
        from simrig.world import TrafficWorld
        from simrig.world.ego_planner import plan, planning_ego
        from simrig.world.phantoms import phantoms_from_boxes
        from simrig.world.traffic import EGO_CLASS
        from simrig.world.vehicles import VEHICLE_TYPES

        self._plan, self._planning_ego, self._phantoms = plan, planning_ego, phantoms_from_boxes
        self._ego_type = VEHICLE_TYPES[EGO_CLASS]
        world = TrafficWorld(traffic, frame_rate_hz, env_seed=RandomStreams(seed).integer_seed("traffic"),
                             rng=stream_generator("planning_road"))
        self.road, self.route = world.planning_road()
        self._world = world  # keeps highway-env's environment (and its road) alive
        self.target_speed = traffic.ego_speed_mps

    def ego(self, pose):
        """The ego's planner at ``pose`` (:func:`~simrig.world.ego_planner.planning_ego`)."""
        return self._planning_ego(self.road, self._ego_type, pose, self.target_speed, self.route)

    def plan(self, ego, boxes: np.ndarray, idents: np.ndarray) -> EgoPlan:
        """What ``ego``'s planner commands on world boxes ``(N, 9)`` with ``idents`` ``(N,)``."""
        return self.plan_on(ego, self.phantoms(boxes, idents))

    def phantoms(self, boxes: np.ndarray, idents: np.ndarray) -> list:
        """The :mod:`~simrig.world.phantoms` of world boxes ``(N, 9)`` with ``idents`` ``(N,)``: built once, they
        keep the lanes they were found on for every later query on them."""
        return self._phantoms(self.road, boxes, idents)

    def plan_on(self, ego, phantoms: list, known: dict | None = None) -> EgoPlan:
        """What ``ego``'s planner commands on ``phantoms`` (``known``: neighbour-search answers still true of them,
        :func:`~simrig.world.ego_planner.plan`)."""
        return self._plan(ego, phantoms, self.road, known)


def planner_road_of(dataset: Dataset) -> PlanningRoad | None:
    """The planning road of ``dataset``; None for a dataset simrig did not simulate (an imported one)."""
    if dataset.source is not None:
        return None
    from simrig.scenarios.schema import scenario_from_record  # a simulated dataset's scenario, validated again

    scenario = scenario_from_record(dataset.scenario, f"dataset {dataset.path}")
    return PlanningRoad(scenario.traffic, scenario.frame_rate_hz, dataset.seed)


def planner_scores(road: PlanningRoad, truth: GroundTruth, tracks3d: TrackRows, misses: np.ndarray,
                   truth_side: TruthSide) -> PlannerScores:
    """Open-loop planner-aware scores of ``tracks3d`` (world frame, relative to the true ego) against ``truth``,
    whose plans are ``truth_side`` (:func:`simrig.scoring.truth_plans.truth_side_of`: recorded with the dataset, so
    each frame costs one query, on the tracks); ``misses`` ``(n, 2)``: the (frame, actor id) of every 3D FN, each
    weighed by its consequence (module docstring)."""
    track_rows = np.flatnonzero(in_class_range(truth, tracks3d.frame, tracks3d.label, tracks3d.boxes))
    track_bounds = np.searchsorted(tracks3d.frame[track_rows], np.stack([truth.frames, truth.frames + 1]))
    f = len(truth.frames)
    a_truth, lane_truth, leader_truth = truth_side.acceleration, truth_side.lane_change, truth_side.leader
    a_tracks, lane_tracks, leader_tracks = np.zeros(f), np.zeros(f, np.int8), np.full(f, -1, np.int64)
    for position in range(f):
        t = track_rows[track_bounds[0, position]:track_bounds[1, position]]
        ego = road.ego(truth.egos[position]) if truth_side.egos is None else truth_side.egos[position]
        on_tracks = road.plan(ego, tracks3d.boxes[t], tracks3d.track_id[t])
        a_tracks[position], lane_tracks[position], leader_tracks[position] = (on_tracks.acceleration,
                                                                              on_tracks.lane_change, on_tracks.leader)
    consequence = {pair: truth_side.consequence[pair]
                   for pair in map(tuple, np.asarray(misses, dtype=np.int64).reshape(-1, 2).tolist())
                   if pair in truth_side.consequence}
    kl = divergence(a_truth, lane_truth, a_tracks, lane_tracks)
    missed = (a_truth <= -HAZARD_MPS2) & (a_tracks - a_truth >= HAZARD_MPS2)
    invented = (a_tracks <= -HAZARD_MPS2) & (a_truth - a_tracks >= HAZARD_MPS2)
    hazard = np.where(missed, "missed", np.where(invented, "invented", ""))
    frames = pa.table({
        "frame": truth.frames.astype(np.int32), "acceleration_truth": a_truth, "acceleration_tracks": a_tracks,
        "lane_change_truth": lane_truth, "lane_change_tracks": lane_tracks, "leader_truth": leader_truth,
        "leader_tracks": leader_tracks, "divergence": kl, "hazard": hazard.astype(str),
    }, schema=PLAN_SCHEMA)
    metrics = {
        "PKL": float(kl.mean()) if f else float("nan"),
        "dACC": float(np.abs(a_tracks - a_truth).mean()) if f else float("nan"),
        "LANE": int((lane_truth != lane_tracks).sum()),
        "HZ_MISS": int(missed.sum()),
        "HZ_FAKE": int(invented.sum()),
    }
    return PlannerScores(metrics, frames, consequence)
