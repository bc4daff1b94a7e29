"""Appearance (re-ID) embeddings with memory, shaped like a real re-ID model's, and the same whichever camera looks.

What two observations of one actor look like depends on the change of view between them — the angle between the
viewing directions (the side of the car seen), the time between them, occlusion, truncation and distance — not on
whether one camera or two made them. An actor seen along the viewing bearing θ (the direction of the ray from the
camera to the actor, in the actor's own frame) has the appearance

    a(θ) = unit(√(1 − v) · identity + √v · view(θ)),   identity = unit(√(1 − w) · own + √w · lookalike[class, colour])
    view(θ) = unit(Σ_k exp(−δ(θ, φ_k)² / (2 λ²)) · u_k)

with ``own`` and the view anchors ``u_k`` fixed random unit vectors per actor (the ``embeddings`` stream, per actor
id) at bearings φ_k every :data:`ANCHOR_SPACING_DEG`, δ the wrapped angle between bearings, λ =
``viewpoint_scale_deg``, ``lookalike`` one per (class, colour) pair, w = ``lookalike_weight``, v =
``viewpoint_weight``. view(θ) turns smoothly as the bearing turns: two cameras of a stereo pair 0.54 m apart see a
car 20 m away along bearings 1.5° apart, and the cameras of a surround ring, mounted together, see it along
bearings as close, so both see nearly the same a(θ); a car overtaken is seen from behind, the side and the front
in turn. An observation by camera c at frame t is

    e = unit(a(θ) + g · (s_f · x_f(t) + s_s · x_s(t)) + σ · n / √D)

with n standard normal, drawn afresh per observation (per camera: the image's own noise), σ = (sigma +
occlusion_sigma · occlusion + truncation_sigma · truncation) · g, g = (1 + d / distance_scale_m) · noise factor,
and x_f, x_s two drifts with memory per actor: Ornstein–Uhlenbeck processes in ℝᴰ with stationary covariance I/D
(so |x| ≈ 1) and correlation times ``drift_time_s`` and ``slow_drift_time_s``, s_f = ``drift_sigma``, s_s =
``slow_drift_sigma``. The drifts are the actor's look changing in time (pose, lighting, dirt): every camera sees
the same drift at the same instant, and two observations g frames apart share a fraction exp(−g·Δt/τ) of each, so
an actor looks less like itself the longer it is away. Two synchronised cameras therefore differ by their images'
noise and the small change of bearing alone, and land where one camera's gap-1 pairs land or closer. The drifts
are advanced for every actor in the frame's actor list, seen or not, from their own stream, so their draws never
depend on another cause's settings.

With ``target_auc`` set, ``sigma`` is solved for by bisection on a Monte Carlo estimate (a fixed stream,
common random numbers) of the ROC AUC of cosine distance between same-identity pairs (two observations of
one appearance) and different-identity pairs (two actors with classes from the traffic's class mix and
uniform colours, seen along the same bearing) at the reference condition: unoccluded, untruncated, d → 0.
"""

from __future__ import annotations

import numpy as np

from simrig.scenarios.sensor_schema import EmbeddingConfig

from ..geometry import viewing_bearings
from ..seeding import RandomStreams
from .batch import SensorBatch
from .processes import GaussMarkov, ar1_coefficient

ANCHOR_SPACING_DEG = 15.0
"""[deg] bearings of an actor's view anchors (24 around it): fine beside any kernel width above ~10°."""
_ANCHORS = int(round(360.0 / ANCHOR_SPACING_DEG))
_ANCHOR_BEARINGS = np.deg2rad(np.arange(_ANCHORS) * ANCHOR_SPACING_DEG)
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


def view_weights(bearings: np.ndarray, scale_deg: float) -> np.ndarray:
    """``(K, anchors)`` weights of the view anchors at ``bearings`` [rad]: a Gaussian of the wrapped angle to each
    anchor, width ``scale_deg``."""
    delta = (bearings[:, None] - _ANCHOR_BEARINGS[None, :] + np.pi) % (2 * np.pi) - np.pi
    return np.exp(-0.5 * (delta / np.deg2rad(scale_deg)) ** 2)


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
        """(own unit vector, colour, view anchors (anchors, D)) of an actor, from its ``embeddings`` stream."""
        if actor_id not in self._actors:
            rng = self._streams.generator("embeddings", int(actor_id))
            d = self.config.dimension
            own = _unit(rng.standard_normal(d))
            colour = int(rng.integers(self.config.colours))
            views = _unit(rng.standard_normal((_ANCHORS, d)))
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

    def appearance(self, actor_ids: np.ndarray, labels: np.ndarray, bearings: np.ndarray) -> np.ndarray:
        """Noise-free unit appearance vectors ``(N, D)`` of actors seen along ``bearings`` [rad]
        (:func:`viewing_bearings`)."""
        v = self.config.viewpoint_weight
        identities = np.stack([self.identity(actor_id, str(label))
                               for actor_id, label in zip(actor_ids.tolist(), labels, strict=True)])
        if v == 0:
            return identities
        anchors = np.stack([self._actor(actor_id)[2] for actor_id in actor_ids.tolist()])  # (N, anchors, D)
        views = _unit(np.einsum("nk,nkd->nd", view_weights(bearings, self.config.viewpoint_scale_deg), anchors))
        return _unit(np.sqrt(1 - v) * identities + np.sqrt(v) * views)

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
        views = _unit(rng.standard_normal((2, m, d)))  # one bearing, shared by a pair: its view vector
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
        """The drifts s_f·x_f + s_s·x_s ``(N, D)`` of the frame's actors, the same for every camera, advanced one
        frame (None when both are off): 2·N·D normals from the drift stream."""
        if self._drift is None:
            return None
        n, d = len(batch), self.config.dimension
        z = self._camera_stream(_DRIFT_STREAM, 0).standard_normal((n, 2 * d))
        state = self._drift.step(batch.actor_ids, z).reshape(n, 2, d) / np.sqrt(d)
        return np.einsum("njd,j->nd", state, self.drift_scales)

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
            bearings = viewing_bearings(batch.boxes3d[cameras, actors], batch.world_from_camera[cameras, :3, 3])
            appearance = self.appearance(batch.actor_ids[actors], batch.classes[actors], bearings)
            disturbance = noise[cameras, actors] * sigma[cameras, actors, None]
            if drift is not None:
                disturbance += drift[actors] * growth[cameras, actors, None]
            embeddings[cameras, actors] = _unit(appearance + disturbance) if self.enabled else appearance
        batch.embeddings = embeddings
