"""Appearance (re-ID) embeddings with memory, shaped like a real re-ID model's.

An actor's appearance seen from side s (back, side, front) is

    a = unit(√(1 − v) · identity + √v · view_s),   identity = unit(√(1 − w) · own + √w · lookalike[class, colour])

with ``own`` and the three ``view`` vectors fixed random unit vectors per actor (the ``embeddings`` stream,
per actor id), ``lookalike`` one per (class, colour) pair, w = ``lookalike_weight``, v = ``viewpoint_weight``.
An observation by camera c at frame t is

    e = unit(a + g · (s_f · x_f(t) + s_s · x_s(t)) + σ · n / √D)

with n standard normal (white, drawn afresh per frame), σ = (sigma + occlusion_sigma · occlusion +
truncation_sigma · truncation) · g, g = (1 + d / distance_scale_m) · noise factor, and x_f, x_s two drifts with
memory per (actor, camera): Ornstein–Uhlenbeck processes in ℝᴰ with stationary covariance I/D (so |x| ≈ 1)
and correlation times ``drift_time_s`` and ``slow_drift_time_s``, s_f = ``drift_sigma``, s_s =
``slow_drift_sigma``. Two observations g frames apart by one camera share a fraction exp(−g·Δt/τ) of each
drift, so an actor looks less like itself the longer it is away (as the features of a real re-ID model do:
pose, lighting and occlusion change); two cameras see independent drifts of the same actor. The drifts are
advanced for every actor in the frame's actor list, seen or not, from their own stream per camera, so their
draws never depend on another cause's settings.

With ``target_auc`` set, ``sigma`` is solved for by bisection on a Monte Carlo estimate (a fixed stream,
common random numbers) of the ROC AUC of cosine distance between same-identity pairs (two observations of
one appearance) and different-identity pairs (two actors with classes from the traffic's class mix and
uniform colours, from the same side) at the reference condition: unoccluded, untruncated, d → 0.
"""

from __future__ import annotations

import numpy as np

from simrig.scenarios.sensor_schema import EmbeddingConfig

from ..seeding import RandomStreams
from .batch import SensorBatch
from .processes import GaussMarkov, ar1_coefficient

_SIDES = 3  # back, side, front
_CALIBRATION_STREAM = 10
_LOOKALIKE_STREAM = 11
_NOISE_STREAM = 4  # the embedding noise's stream key since the first sensor model: never renumber
_DRIFT_STREAM = 15
_SOLVED_SIGMA: dict[tuple, float] = {}
"""σ solved for a target AUC, by (seed, embedding settings, classes, class weights, target): see ``_solved_sigma``."""
_CALIBRATION_PAIRS = 4000


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.maximum(np.linalg.norm(vectors, axis=-1, keepdims=True), 1e-12)


def roc_auc(positive: np.ndarray, negative: np.ndarray) -> float:
    """ROC AUC of scores where ``positive`` should rank above ``negative`` (Mann–Whitney, ties count ½).

    >>> roc_auc(np.array([0.9, 0.8]), np.array([0.1, 0.85]))
    0.75
    """
    from scipy.stats import rankdata

    ranks = rankdata(np.concatenate([positive, negative]))
    n_pos, n_neg = len(positive), len(negative)
    return float((ranks[:n_pos].sum() - n_pos * (n_pos + 1) / 2) / (n_pos * n_neg))


def _viewed_side(boxes3d: np.ndarray, camera_centre: np.ndarray) -> np.ndarray:
    """Which side of each box the camera sees: 0 back, 1 side, 2 front (from the bearing of the camera's ray
    relative to the box's yaw); ``camera_centre`` ``(3,)``, or ``(K, 3)``: one per box."""
    ray = boxes3d[:, :2] - camera_centre[..., :2]
    relative = np.abs((np.arctan2(ray[:, 1], ray[:, 0]) - boxes3d[:, 6] + np.pi) % (2 * np.pi) - np.pi)
    return np.where(relative < np.pi / 4, 0, np.where(relative > 3 * np.pi / 4, 2, 1))


class Embeddings:
    """The embedding effect (see the module docstring); ``identity(actor_id)`` is an actor's noise-free
    identity vector."""

    def __init__(self, streams: RandomStreams, config: EmbeddingConfig, class_mix: dict[str, float] | None = None,
                 *, enabled: bool = True, period_s: float = 0.1):
        self._streams = streams
        self.period_s = period_s
        self.enabled = enabled  # false: noise drawn but not added (a counterfactual run)
        self.config = config
        self.class_names = list(class_mix or {"car": 1.0})
        weights = np.array([(class_mix or {"car": 1.0})[name] for name in self.class_names], dtype=float)
        self.class_weights = weights / weights.sum()
        self._actors: dict[int, tuple[np.ndarray, int, np.ndarray]] = {}
        self._lookalike: dict[tuple[str, int], np.ndarray] = {}
        self._appearance: dict[tuple[int, int], np.ndarray] = {}  # (actor id, side) → appearance
        self._generators: dict[tuple[int, int], np.random.Generator] = {}
        self.drift_scales = np.array([config.drift_sigma, config.slow_drift_sigma])
        self.drift_phi = np.array([ar1_coefficient(period_s, config.drift_time_s),
                                   ar1_coefficient(period_s, config.slow_drift_time_s)])
        self._drift = GaussMarkov(np.repeat(self.drift_phi, config.dimension)) if self.drift_scales.any() else None
        self.sigma = config.sigma if config.target_auc is None else self._solved_sigma(config.target_auc)

    # ------------------------------------------------------------------ fixed vectors
    def _actor(self, actor_id: int) -> tuple[np.ndarray, int, np.ndarray]:
        """(own unit vector, colour, view unit vectors (3, D)) of an actor, from its ``embeddings`` stream."""
        if actor_id not in self._actors:
            rng = self._streams.generator("embeddings", int(actor_id))
            d = self.config.dimension
            own = _unit(rng.standard_normal(d))
            colour = int(rng.integers(self.config.colours))
            views = _unit(rng.standard_normal((_SIDES, d)))
            self._actors[actor_id] = (own, colour, views)
        return self._actors[actor_id]

    def _lookalike_vector(self, label: str, colour: int) -> np.ndarray:
        key = (label, colour)
        if key not in self._lookalike:
            index = self.class_names.index(label) if label in self.class_names else len(self.class_names)
            rng = self._streams.generator("sensor", _LOOKALIKE_STREAM, index, colour)
            self._lookalike[key] = _unit(rng.standard_normal(self.config.dimension))
        return self._lookalike[key]

    def identity(self, actor_id: int, label: str = "car") -> np.ndarray:
        """The noise-free unit identity vector of ``actor_id`` (same for every camera, frame and side)."""
        own, colour, _ = self._actor(actor_id)
        w = self.config.lookalike_weight
        if w == 0:
            return own
        return _unit(np.sqrt(1 - w) * own + np.sqrt(w) * self._lookalike_vector(label, colour))

    def appearance(self, actor_ids: np.ndarray, labels: np.ndarray, sides: np.ndarray) -> np.ndarray:
        """Noise-free unit appearance vectors ``(N, D)`` of actors seen from ``sides``."""
        d, v = self.config.dimension, self.config.viewpoint_weight
        out = np.empty((len(actor_ids), d))
        for row, (actor_id, label, side) in enumerate(zip(actor_ids.tolist(), labels, sides.tolist(), strict=True)):
            key = (actor_id, side)
            if key not in self._appearance:
                identity = self.identity(actor_id, str(label))
                self._appearance[key] = identity if v == 0 else _unit(
                    np.sqrt(1 - v) * identity + np.sqrt(v) * self._actor(actor_id)[2][side])
            out[row] = self._appearance[key]
        return out

    # ------------------------------------------------------------------ calibration
    def _solved_sigma(self, target_auc: float) -> float:
        """:meth:`solve_sigma`, remembered per process for the same seed, settings and classes (a pure function of
        them: a counterfactual explanation builds the sensor model again for every coalition of one run)."""
        key = (self._streams.seed, self.config.model_dump_json(), tuple(self.class_names),
               self.class_weights.tobytes(), float(target_auc), self.period_s)
        if key not in _SOLVED_SIGMA:
            _SOLVED_SIGMA[key] = self.solve_sigma(target_auc)
        return _SOLVED_SIGMA[key]

    def solve_sigma(self, target_auc: float) -> float:
        """σ whose reference-condition ROC AUC of same-identity pairs one frame apart against different-identity
        pairs is ``target_auc`` (bisection)."""
        c = self.config
        d, m = c.dimension, _CALIBRATION_PAIRS
        rng = self._streams.generator("sensor", _CALIBRATION_STREAM)
        own = _unit(rng.standard_normal((2, m, d)))
        views = _unit(rng.standard_normal((2, m, d)))
        classes = rng.choice(len(self.class_names), size=(2, m), p=self.class_weights)
        colours = rng.integers(c.colours, size=(2, m))
        noise = rng.standard_normal((3, m, d)) / np.sqrt(d)
        w, v = c.lookalike_weight, c.viewpoint_weight
        drift = np.zeros((3, m, d))
        if self._drift is not None:  # the first two observations are one frame apart: they share most of it
            for scale, phi in zip(self.drift_scales, self.drift_phi, strict=True):
                now = rng.standard_normal((2, m, d)) / np.sqrt(d)
                later = phi * now[0] + np.sqrt(1 - phi**2) * rng.standard_normal((m, d)) / np.sqrt(d)
                drift += scale * np.stack([now[0], later, now[1]])
        prototypes = _unit(rng.standard_normal((len(self.class_names), c.colours, d)))
        identity = _unit(np.sqrt(1 - w) * own + np.sqrt(w) * prototypes[classes, colours])
        appearance = _unit(np.sqrt(1 - v) * identity + np.sqrt(v) * views)

        def auc(sigma: float) -> float:
            first = _unit(appearance[0] + drift[0] + sigma * noise[0])
            same = np.sum(first * _unit(appearance[0] + drift[1] + sigma * noise[1]), axis=1)
            different = np.sum(first * _unit(appearance[1] + drift[2] + sigma * noise[2]), axis=1)
            return roc_auc(same, different)

        low, high = 0.0, 1.0
        while auc(high) > target_auc and high < 1e3:
            low, high = high, high * 2
        for _ in range(40):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if auc(middle) > target_auc else (low, middle)
        return 0.5 * (low + high)

    # ------------------------------------------------------------------ the effect
    def _camera_stream(self, key: int, camera_index: int) -> np.random.Generator:
        """Camera ``camera_index``'s generator of the sensor stream ``key`` (made once)."""
        if (key, camera_index) not in self._generators:
            self._generators[key, camera_index] = self._streams.generator("sensor", key, camera_index)
        return self._generators[key, camera_index]

    def rng(self, camera_index: int) -> np.random.Generator:
        return self._camera_stream(_NOISE_STREAM, camera_index)

    def drift(self, batch: SensorBatch) -> np.ndarray | None:
        """The drifts s_f·x_f + s_s·x_s ``(C, N, D)`` of every camera's actors at this frame, advanced one frame
        (None when both are off). Each camera draws 2·N·D normals from its own drift stream."""
        if self._drift is None:
            return None
        n, d, camera_count = len(batch), self.config.dimension, len(batch.cameras)
        z = np.empty((n, camera_count, 2 * d))  # (N, C, 2D)
        for index in range(camera_count):
            z[:, index] = self._camera_stream(_DRIFT_STREAM, index).standard_normal((n, 2 * d))
        state = self._drift.step(batch.actor_ids, z).reshape(n, camera_count, 2, d) / np.sqrt(d)
        return np.einsum("ncjd,j->cnd", state, self.drift_scales)

    def apply(self, batch: SensorBatch) -> None:
        c = self.config
        n, d = len(batch), c.dimension
        noise = np.stack([self.rng(index).standard_normal((n, d)) for index in range(len(batch.cameras))]) / np.sqrt(d)
        drift = self.drift(batch)
        truncation = np.nan_to_num(batch.truncation, nan=1.0)
        sigma = (self.sigma + c.occlusion_sigma * (1.0 - batch.visible_fraction)
                 + c.truncation_sigma * truncation) * batch.noise_factor
        growth = batch.noise_factor
        if c.distance_scale_m:
            sigma = sigma * (1.0 + batch.distance / c.distance_scale_m)
            growth = growth * (1.0 + batch.distance / c.distance_scale_m)
        embeddings = np.full((len(batch.cameras), n, d), np.float32(np.nan), dtype=np.float32)
        cameras, actors = np.nonzero(batch.detected)
        if len(actors):
            sides = _viewed_side(batch.boxes3d[cameras, actors], batch.world_from_camera[cameras, :3, 3])
            appearance = self.appearance(batch.actor_ids[actors], batch.classes[actors], sides)
            disturbance = noise[cameras, actors] * sigma[cameras, actors, None]
            if drift is not None:
                disturbance += drift[cameras, actors] * growth[cameras, actors, None]
            embeddings[cameras, actors] = _unit(appearance + disturbance) if self.enabled else appearance
        batch.embeddings = embeddings
