"""The Stone Soup side of ``tests/perf/users_wait.py``: simulate, track and score a multi-target scene with Stone
Soup alone, in the interpreter of a venv that has it (``python -m venv .cache/stonesoup-venv &&
.cache/stonesoup-venv/bin/pip install stonesoup==1.9.1``). Not simrig code: it imports nothing of simrig.

The scene is sized like ``highway_surround6``: ``--frames`` steps at 10 Hz, about ``--targets`` targets alive
(2D constant velocity, births and deaths), each detected with probability 0.9 under 0.5 m position noise, two
clutter detections a step; tracked by Stone Soup's multi-target tracker (Kalman predictor and updater, global
nearest neighbour on the Mahalanobis distance, two-measurement initiation, deletion after 5 steps unseen), scored
by its OSPA and SIAP metric generators. Prints one JSON line: the CPU seconds of each stage.
"""

import argparse
import datetime
import json
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--targets", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    started = time.process_time()
    from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
    from stonesoup.dataassociator.tracktotrack import TrackToTruth
    from stonesoup.deleter.time import UpdateTimeStepsDeleter
    from stonesoup.hypothesiser.distance import DistanceHypothesiser
    from stonesoup.initiator.simple import MultiMeasurementInitiator
    from stonesoup.measures import Euclidean, Mahalanobis
    from stonesoup.metricgenerator.manager import MultiManager
    from stonesoup.metricgenerator.ospametric import OSPAMetric
    from stonesoup.metricgenerator.tracktotruthmetrics import SIAPMetrics
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import CombinedLinearGaussianTransitionModel, ConstantVelocity
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.simulator.simple import MultiTargetGroundTruthSimulator, SimpleDetectionSimulator
    from stonesoup.tracker.simple import MultiTargetTracker
    from stonesoup.types.array import CovarianceMatrix, StateVector
    from stonesoup.types.state import GaussianState
    from stonesoup.updater.kalman import KalmanUpdater

    imported = time.process_time()
    np.random.seed(args.seed)  # noqa: NPY002 — Stone Soup's simulators draw from numpy's global generator
    rng = np.random.default_rng(args.seed)
    step = datetime.timedelta(seconds=0.1)
    start = datetime.datetime(2026, 1, 1)
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(0.5), ConstantVelocity(0.5)])
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([0.25, 0.25]))
    spread = CovarianceMatrix(np.diag([100.0**2, 3.0**2, 8.0**2, 0.5**2]))
    birth = GaussianState(StateVector([0.0, 25.0, 0.0, 0.0]), spread, timestamp=start)
    truth = MultiTargetGroundTruthSimulator(
        transition_model=transition, initial_state=birth, timestep=step, number_steps=args.frames,
        birth_rate=0.2, death_probability=0.2 / args.targets, preexisting_states=[
            rng.multivariate_normal(birth.state_vector.ravel(), birth.covar) for _ in range(args.targets)])
    detections = SimpleDetectionSimulator(
        groundtruth=truth, measurement_model=measurement, detection_probability=0.9, meas_range=np.array(
            [[-400.0, 600.0], [-50.0, 50.0]]), clutter_rate=2.0)
    predictor, updater = KalmanPredictor(transition), KalmanUpdater(measurement)
    hypothesiser = DistanceHypothesiser(predictor, updater, measure=Mahalanobis(), missed_distance=3.0)
    deleter = UpdateTimeStepsDeleter(time_steps_since_update=5)
    initiator = MultiMeasurementInitiator(
        prior_state=GaussianState(StateVector([0.0, 0.0, 0.0, 0.0]),
                                  CovarianceMatrix(np.diag([1.0, 100.0, 1.0, 100.0]))),
        measurement_model=measurement, deleter=deleter, data_associator=GNNWith2DAssignment(hypothesiser),
        updater=updater, min_points=2)
    tracker = MultiTargetTracker(initiator=initiator, deleter=deleter, detector=detections,
                                 data_associator=GNNWith2DAssignment(hypothesiser), updater=updater)
    tracks = set()
    for _, current in tracker:
        tracks |= current
    tracked = time.process_time()
    ground_truth = truth.groundtruth_paths
    manager = MultiManager([
        OSPAMetric(c=10, p=1, generator_name="OSPA", tracks_key="tracks", truths_key="truths"),
        SIAPMetrics(position_measure=Euclidean((0, 2)), velocity_measure=Euclidean((1, 3)), generator_name="SIAP",
                    tracks_key="tracks", truths_key="truths")],
        associator=TrackToTruth(association_threshold=30))
    manager.add_data({"tracks": tracks, "truths": ground_truth, "detections": detections.detections})
    manager.generate_metrics()
    scored = time.process_time()
    print(json.dumps({"import_s": imported - started, "simulate_and_track_s": tracked - imported,
                      "score_s": scored - tracked, "total_s": scored - started, "tracks": len(tracks),
                      "truths": len(ground_truth)}))


if __name__ == "__main__":
    main()
