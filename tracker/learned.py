"""A learned association: the reference Kalman tracker (``global_hungarian``'s filter, life rule and Hungarian
assignment) whose hand-set Mahalanobis gate is replaced by a model of P(same object | pair features), trained on
simrig data (:mod:`simrig.collection.train`).

The model is a logistic regression on the features of :mod:`.association_features` and their squares, each
standardised: P = σ(b + Σₖ wₖ (φₖ − μₖ) / sₖ). It is stored as JSON (numbers only: loading a model runs no code)
and applied with numpy. A pair's cost is its negative log-odds −ln(P / (1 − P)), so that the Hungarian
assignment maximises the summed log-likelihood ratio of its pairs; a pair may match when P ≥ ``threshold``;
pairs of different classes, or farther apart than ``prefilter_m``, never match.

Appearance: each track keeps an exponential moving average of its detections' embeddings (momentum 0.9, as
DeepSORT's successors), renormalised to a unit vector.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from simrig.types import Rig, SensorFrame

from .assignment import hungarian
from .association_features import TRACK_FEATURES, track_pair_features
from .detections import DetectionArrays
from .kalman_tracker import KalmanTrack, KalmanTracker
from .settings import kalman_tracker_parts

MODEL_FORMAT = "simrig association model"
MAX_MODEL_BYTES = 1 << 20
DEFAULT_MODEL = Path(__file__).resolve().parent / "models" / "association.json"
"""The model ``learned`` uses unless given another: trained on the ``traffic_mix`` collection (the model file
says how: ``trained_on``)."""
APPEARANCE_MOMENTUM = 0.9


class ModelError(ValueError):
    """A model file cannot be read or is not a model; the message names the file and the key."""


def design(features: np.ndarray) -> np.ndarray:
    """(..., 2F) the model's inputs of (..., F) features: each feature, then each feature squared."""
    return np.concatenate([features, features * features], axis=-1)


BOUNDS: dict[str, tuple[float, float]] = {"mean": (-1e9, 1e9), "scale": (1e-9, 1e9), "coef": (-1e6, 1e6)}
"""The range of each array of a model file (and of the intercept: ``coef``'s): wide enough for any fitted model,
narrow enough that the log-odds of any pair stays finite (a coefficient of 1e308 made inf and NaN tracks)."""


def _shown(value, limit: int = 60) -> str:
    """``repr(value)`` cut to ``limit`` characters, for a one-line message."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


@dataclass(frozen=True)
class AssociationModel:
    """Standardised logistic regression on :func:`design` of :data:`TRACK_FEATURES` (module docstring)."""

    mean: tuple[float, ...]
    scale: tuple[float, ...]
    coef: tuple[float, ...]
    intercept: float
    threshold: float = 0.5
    prefilter_m: float = 10.0
    trained_on: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        width = 2 * len(TRACK_FEATURES)
        for key, (low, high) in BOUNDS.items():
            values = getattr(self, key)
            if len(values) != width:
                raise ModelError(f"{key}: {width} numbers (each feature, then its square), got {len(values)}")
            bad = next((i for i, v in enumerate(values) if not (isinstance(v, (int, float))
                                                                and not isinstance(v, bool) and low <= v <= high)),
                       None)
            if bad is not None:
                raise ModelError(f"{key}[{bad}]: a number in [{low:g}, {high:g}], got {_shown(values[bad])}")
        low, high = BOUNDS["coef"]
        if not (isinstance(self.intercept, (int, float)) and low <= self.intercept <= high):
            raise ModelError(f"intercept: a number in [{low:g}, {high:g}], got {_shown(self.intercept)}")
        if not 0 < self.threshold < 1:
            raise ModelError(f"threshold: in (0, 1), got {self.threshold!r}")
        if not self.prefilter_m > 0:
            raise ModelError(f"prefilter_m: positive [m], got {self.prefilter_m!r}")

    def log_odds(self, features: np.ndarray) -> np.ndarray:
        """ln(P / (1 − P)) of (..., F) pair features: the log-likelihood ratio of "same object" (with the
        training set's prior)."""
        z = (design(features) - np.asarray(self.mean)) / np.asarray(self.scale)
        return z @ np.asarray(self.coef) + self.intercept

    def probability(self, features: np.ndarray) -> np.ndarray:
        """P(same object) of (..., F) pair features."""
        return 1.0 / (1.0 + np.exp(-np.clip(self.log_odds(features), -50.0, 50.0)))

    def to_json(self) -> str:
        return json.dumps({"format": MODEL_FORMAT, "features": list(TRACK_FEATURES), "basis": "each feature, then "
                           "its square, standardised", "mean": list(self.mean), "scale": list(self.scale),
                           "coef": list(self.coef), "intercept": self.intercept, "threshold": self.threshold,
                           "prefilter_m": self.prefilter_m, "trained_on": self.trained_on}, indent=1) + "\n"

    @classmethod
    def load(cls, path: str | Path) -> AssociationModel:
        """The model in a JSON file written by :meth:`to_json`; a :class:`ModelError` naming the file otherwise."""
        path = Path(path)
        where = f"model file {str(path)!r}"
        if path.suffix != ".json":
            raise ModelError(f"{where}: a model is a .json file (AssociationModel.to_json)")
        if not path.is_file():  # a FIFO or a device would block or never end
            raise ModelError(f"{where}: {'not a regular file' if path.exists() else 'no such file'}")
        try:
            with path.open("rb") as handle:
                data = handle.read(MAX_MODEL_BYTES + 1)
        except OSError as error:
            raise ModelError(f"{where}: cannot be read ({error.strerror or error})") from None
        if len(data) > MAX_MODEL_BYTES:
            raise ModelError(f"{where}: larger than {MAX_MODEL_BYTES} bytes; not a model")
        try:
            document = json.loads(data)
        except (UnicodeDecodeError, json.JSONDecodeError) as error:
            raise ModelError(f"{where}: not JSON ({error})") from None
        if not isinstance(document, dict) or document.get("format") != MODEL_FORMAT:
            raise ModelError(f"{where}: not a {MODEL_FORMAT} (its 'format' says otherwise)")
        if document.get("features") != list(TRACK_FEATURES):
            raise ModelError(f"{where}: features: {document.get('features')!r} are not this simrig's "
                             f"{list(TRACK_FEATURES)}")
        trained_on = document.get("trained_on", {})
        if not isinstance(trained_on, dict):
            raise ModelError(f"{where}: trained_on: a table of what the model was trained on, got "
                             f"{_shown(trained_on)}")
        try:
            return cls(tuple(document["mean"]), tuple(document["scale"]), tuple(document["coef"]),
                       document["intercept"], document.get("threshold", 0.5), document.get("prefilter_m", 10.0),
                       dict(trained_on))
        except KeyError as error:
            raise ModelError(f"{where}: {error.args[0]}: missing") from None
        except (TypeError, ModelError) as error:
            raise ModelError(f"{where}: {error}") from None


class AppearanceKalmanTracker(KalmanTracker):
    """The reference Kalman tracker keeping what pair features need: each track's appearance (a moving average of
    its detections' embeddings), the step's time and the ego's position. Associates like its ``cost``; its
    :meth:`pair_features` are what a learned model sees (the training loader records them from this class)."""

    def __init__(self, **parts):
        super().__init__(**parts)
        self.appearance: dict[int, np.ndarray] = {}
        self._dt = 0.0
        self._ego_xy = np.zeros(2)

    def reset(self, *, rig: Rig, seed: int | None = None) -> None:
        super().reset(rig=rig, seed=seed)
        self.appearance = {}

    def step(self, frame: SensorFrame) -> list:
        self._ego_xy = np.array([frame.ego.x, frame.ego.y], dtype=float)
        return super().step(frame)

    def step_arrays(self, detections: DetectionArrays, dt: float) -> None:
        self._dt = float(dt)
        super().step_arrays(detections, dt)
        alive = {track.track_id for track in self.tracks}
        self.appearance = {key: value for key, value in self.appearance.items() if key in alive}

    def pair_features(self, detections: DetectionArrays, tracks: list[KalmanTrack] | None = None) -> np.ndarray:
        """(N, M, F) features of every (track, detection) pair (:mod:`.association_features`), each track
        predicted to each detection's capture time."""
        tracks = self.tracks if tracks is None else tracks
        n, m = len(tracks), len(detections)
        features = np.zeros((n, m, len(TRACK_FEATURES)))
        if n == 0 or m == 0:
            return features
        dimension = detections.embeddings.shape[1]
        embeddings = np.stack([self.appearance.get(track.track_id, np.full(dimension, np.nan)) for track in tracks])
        since = np.array([track.life.since_update + self._dt for track in tracks])
        hits = np.array([track.life.hits for track in tracks])
        ranges = np.hypot(detections.boxes3d[:, 0] - self._ego_xy[0], detections.boxes3d[:, 1] - self._ego_xy[1])
        for columns, predicted, innovation in self.predictions(detections, tracks):
            features[:, columns] = track_pair_features(
                predicted, innovation, embeddings, since, hits, detections.boxes3d[columns],
                detections.scores[columns], detections.embeddings[columns], ranges[columns])
        return features

    def update(self, detections: DetectionArrays, owner: np.ndarray) -> dict[int, float]:
        scores = super().update(detections, owner)
        for j in np.flatnonzero(owner >= 0):
            self._remember(self.tracks[int(owner[j])].track_id, detections.embeddings[j])
        return scores

    def births(self, detections: DetectionArrays, owner: np.ndarray) -> None:
        known = len(self.tracks)
        super().births(detections, owner)
        unmatched = np.flatnonzero(owner < 0)
        for track in self.tracks[known:]:  # the detection each was born from: the nearest unmatched one
            if len(unmatched):
                position = detections.boxes3d[unmatched, :2]
                self.newborn(track, detections, int(unmatched[np.argmin(np.hypot(*(position - track.kf.x[:2, 0]).T))]))

    def newborn(self, track: KalmanTrack, detections: DetectionArrays, source: int) -> None:
        """A hook for each track born this frame, with the index of the detection it was born from."""
        self._remember(track.track_id, detections.embeddings[source])

    def _remember(self, track_id: int, embedding: np.ndarray) -> None:
        if embedding.size == 0 or not np.all(np.isfinite(embedding)):
            return
        old = self.appearance.get(track_id)
        mixed = embedding if old is None else APPEARANCE_MOMENTUM * old + (1 - APPEARANCE_MOMENTUM) * embedding
        norm = float(np.linalg.norm(mixed))
        if norm > 0:
            self.appearance[track_id] = mixed / norm


@dataclass(frozen=True)
class LearnedCost:
    """The cost of a pair is minus its log-odds of being the same object (so the Hungarian assignment maximises the
    summed log-likelihood ratio of its pairs); the gate is minus the log-odds of ``threshold``."""

    model: AssociationModel

    @property
    def gate(self) -> float:
        return -math.log(self.model.threshold / (1.0 - self.model.threshold))


class LearnedTracker(AppearanceKalmanTracker):
    """:class:`AppearanceKalmanTracker` associating by a learned model (module docstring)."""

    def cost_matrix(self, detections: DetectionArrays, tracks: list[KalmanTrack] | None = None) -> np.ndarray:
        tracks = self.tracks if tracks is None else tracks
        if len(tracks) == 0 or len(detections) == 0:
            return np.zeros((len(tracks), len(detections)))
        features = self.pair_features(detections, tracks)
        model = self.cost.model
        cost = -model.log_odds(features)
        labels = np.array([track.label for track in tracks])
        allowed = (labels[:, None] == detections.labels[None, :]) & (features[..., 1] <= model.prefilter_m)
        return np.where(allowed, cost, np.inf)


def learned(*, model: str | None = None, threshold: float | None = None, life: str = "hits", min_hits: int = 1,
            max_age_s: float = 1.0, score_threshold: float = 0.0, measurement_variance: float = 1.0,
            motion_compensation: bool = True) -> LearnedTracker:
    """model: a model file (:meth:`AssociationModel.to_json`; default: the packaged one, trained on the
    ``traffic_mix`` collection); threshold: P(same object) a pair needs to match (default: the model's);
    the rest as for ``global_hungarian``, whose filter, life rule and Hungarian assignment it shares."""
    loaded = AssociationModel.load(DEFAULT_MODEL if model is None else model)
    if threshold is not None:
        loaded = AssociationModel(loaded.mean, loaded.scale, loaded.coef, loaded.intercept, float(threshold),
                                  loaded.prefilter_m, loaded.trained_on)
    parts = kalman_tracker_parts(cost="mahalanobis", gate=None, life=life, min_hits=min_hits, max_age_s=max_age_s,
                                 measurement_variance=measurement_variance, score_threshold=score_threshold,
                                 motion_compensation=motion_compensation)
    parts["cost"] = LearnedCost(loaded)
    return LearnedTracker(**parts, assign=hungarian)
