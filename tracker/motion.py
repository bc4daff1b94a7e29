"""Constant-velocity Kalman filter on filterpy, AB3DMOT-style, with the real time step in seconds.

State ``x`` (10,): [x, y, z, l, w, h, θ, vx, vy, vz] in the world frame [m, m, rad, m/s] — AB3DMOT's
state with its components in the order of :data:`~simrig.types.BOX3D_FIELDS`; measurement ``z`` (7,):
[x, y, z, l, w, h, θ], the first seven columns of a 3D box.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import KalmanFilter

from .angles import wrap

MEASURED = 7
"""Measured state components: [x, y, z, l, w, h, θ]."""
HEADING = 6
"""Index of θ in the state and the measurement."""


@dataclass(frozen=True)
class KalmanConfig:
    """Diagonals of the filter's matrices (AB3DMOT's values; units follow the state).

    initial_variance: P₀ of the 7 measured components [m², rad²]; initial_velocity_variance: P₀ of the
    velocity [(m/s)²] (unobserved at birth); process_variance: Q of the measured components per second
    [m²/s, rad²/s]; process_velocity_variance: Q of the velocity per second [(m/s)²/s];
    measurement_variance: R [m², rad²]; birth_velocity_variance: P₀ of the velocity [(m/s)²] when the
    starting detection carries a velocity estimate (monocular 3D detectors do).

    Q scales with Δt, so a dropped frame widens the prediction as a longer step should. The defaults are
    AB3DMOT's (Weng et al., IROS 2020; its code's ``KF``: Q = I with the velocity block × 0.01), which are per
    frame at KITTI's 10 Hz with the velocity in metres per frame: 1 m² and 0.01 (m/frame)² = 1 (m/s)² a
    0.1 s step, i.e. 10 m²/s and 10 (m/s)²/s here — so a 10 Hz run steps with exactly AB3DMOT's Q, and other
    rates with the same noise per second. Its P₀ of the velocity, 10⁴ (m/frame)² = 10⁶ (m/s)², is kept at
    10⁴ (m/s)² (a standard deviation of 100 m/s is already no knowledge of a car's speed).
    """

    initial_variance: float = 10.0
    initial_velocity_variance: float = 10000.0
    process_variance: float = 10.0
    process_velocity_variance: float = 10.0
    measurement_variance: float = 1.0
    birth_velocity_variance: float = 4.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"KalmanConfig.{name}: must be a positive number, got {value!r}")

    @property
    def measurement_noise(self) -> np.ndarray:
        """R, (7, 7)."""
        return np.eye(MEASURED) * self.measurement_variance


_H = np.hstack([np.eye(MEASURED), np.zeros((MEASURED, 3))])


def new_filter(box: np.ndarray, config: KalmanConfig) -> KalmanFilter:
    """A filter started at a detected box (9,) [x, y, z, l, w, h, yaw, vx, vy] — the first seven are the
    measurement z; the velocity is taken from the box when finite (variance ``birth_velocity_variance``),
    else started at 0 with ``initial_velocity_variance`` (AB3DMOT)."""
    kf = KalmanFilter(dim_x=10, dim_z=MEASURED)
    kf.H = _H.copy()
    known = box.shape[0] >= 9 and bool(np.all(np.isfinite(box[7:9])))
    velocity = [box[7], box[8], 0.0] if known else [0.0, 0.0, 0.0]
    kf.x = np.concatenate([box[:MEASURED], velocity])[:, None]
    velocity_variance = config.birth_velocity_variance if known else config.initial_velocity_variance
    kf.P = np.diag([config.initial_variance] * MEASURED + [velocity_variance] * 3)
    kf.R = config.measurement_noise
    return kf


def predict(kf: KalmanFilter, dt: float, config: KalmanConfig) -> None:
    """Constant velocity over ``dt`` seconds: x ← F x, P ← F P Fᵀ + Q·dt."""
    F, Q = _transition(dt, config)
    kf.predict(F=F, Q=Q)
    kf.x[HEADING, 0] = wrap(kf.x[HEADING, 0])


@functools.lru_cache(maxsize=64)
def _transition(dt: float, config: KalmanConfig) -> tuple[np.ndarray, np.ndarray]:
    """F and Q·dt for a step of ``dt`` seconds, read-only — every track of a tracker steps by the same few Δt,
    so they are built once per Δt."""
    F = np.eye(10)
    F[0, 7] = F[1, 8] = F[2, 9] = dt
    Q = np.diag([config.process_variance] * MEASURED + [config.process_velocity_variance] * 3) * max(dt, 1e-6)
    F.setflags(write=False)
    Q.setflags(write=False)
    return F, Q


def update(kf: KalmanFilter, z: np.ndarray) -> None:
    """One measurement update with orientation correction: if the measured heading is more than 90° from
    the track's, the track's heading is turned by π first (a box facing backwards is the same box)."""
    theta = kf.x[HEADING, 0]
    if abs(wrap(z[HEADING] - theta)) > np.pi / 2:
        kf.x[HEADING, 0] = wrap(theta + np.pi)
    z = z.copy()
    z[HEADING] = kf.x[HEADING, 0] + wrap(z[HEADING] - kf.x[HEADING, 0])  # on the same branch as the state
    kf.update(z)
    kf.x[HEADING, 0] = wrap(kf.x[HEADING, 0])


def innovation_covariances(P: np.ndarray, config: KalmanConfig) -> np.ndarray:
    """S = H P Hᵀ + R for a stack of state covariances ``P`` (N, 10, 10) → (N, 7, 7)."""
    return P[:, :MEASURED, :MEASURED] + config.measurement_noise


def velocity(x: np.ndarray) -> tuple[float, float]:
    """World-frame (vx, vy) [m/s] of a state (10,)."""
    return float(x[7]), float(x[8])
