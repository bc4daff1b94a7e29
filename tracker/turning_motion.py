"""Turning motion models for the modern filter baseline: CTRA and a bicycle-like constant-curvature model,
as extended Kalman filters on filterpy.

Category-specific motion models are the first idea of Poly-MOT (Li, Xie, Liu, Gao, Dai, Jiang, Zhao, Wang:
"Poly-MOT: A Polyhedral Framework For 3D Multi-Object Tracking", IROS 2023), kept by Fast-Poly (Li, Liu, Wu,
Wu, Zhao, Gao: "Fast-Poly: A Fast Polyhedral Framework For 3D Multi-Object Tracking", RA-L 2024): a car turns
about its own centre at a yaw rate (CTRA: constant turn rate and acceleration), a two-wheeler follows its
front wheel (bicycle model: the heading changes with distance travelled, never on the spot).

State ``x`` (10,): [x, y, z, l, w, h, θ, v, a, r] in the world frame — the measured box first (so the
measurement is the first seven components, as :mod:`.motion`), then the speed along the heading v [m/s], its
rate a [m/s²] and r: the yaw rate ω [rad/s] (``CTRA``) or the path curvature κ [1/m] (``BICYCLE``, ω = v κ:
the kinematic bicycle with a constant steering angle, κ = tan δ / wheelbase).

Prediction over Δt (both models): ω as above, travelled distance s = v Δt + ½ a Δt², heading at mid-step
φ = θ + ½ ω Δt; x += s cos φ, y += s sin φ, θ += ω Δt, v += a Δt. The mid-step heading is second-order
accurate in ω Δt (the closed form of CTRA divides by ω; at 10 Hz the two differ by under 1 cm for a car at
30 m/s turning at 0.5 rad/s). The covariance goes through the Jacobian F of this map: P ← F P Fᵀ + Q Δt.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from filterpy.kalman import KalmanFilter

from .angles import wrap
from .motion import HEADING, MEASURED, KalmanConfig

SPEED, ACCELERATION, TURN = 7, 8, 9
"""Indices of v, a and r in the state."""
_H = np.hstack([np.eye(MEASURED), np.zeros((MEASURED, 3))])


@dataclass(frozen=True)
class TurningModel:
    """One turning model. curvature: r is κ (bicycle) rather than ω (CTRA); process: Q per second of the
    10 state components [units² / s]; turn_variance: P₀ of r at birth."""

    name: str
    curvature: bool
    process: tuple[float, ...]
    turn_variance: float

    def new_filter(self, box: np.ndarray, config: KalmanConfig) -> KalmanFilter:
        """A filter started at a detected box (9,) [x, y, z, l, w, h, yaw, vx, vy]; the speed is the
        detection's velocity along its heading when given (variance ``birth_velocity_variance``), else 0
        (``initial_velocity_variance``); a = r = 0."""
        kf = KalmanFilter(dim_x=10, dim_z=MEASURED)
        kf.H = _H.copy()
        known = box.shape[0] >= 9 and bool(np.all(np.isfinite(box[7:9])))
        speed = float(box[7] * np.cos(box[6]) + box[8] * np.sin(box[6])) if known else 0.0
        kf.x = np.concatenate([box[:MEASURED], [speed, 0.0, 0.0]])[:, None]
        speed_variance = config.birth_velocity_variance if known else config.initial_velocity_variance
        kf.P = np.diag([config.initial_variance] * MEASURED + [speed_variance, 4.0, self.turn_variance])
        kf.R = config.measurement_noise
        return kf

    def predict(self, kf: KalmanFilter, dt: float, config: KalmanConfig) -> None:
        """The EKF prediction over ``dt`` seconds (module docstring)."""
        x = kf.x[:, 0]
        theta, v, a, r = x[HEADING], x[SPEED], x[ACCELERATION], x[TURN]
        omega = v * r if self.curvature else r
        s = v * dt + 0.5 * a * dt * dt
        phi = theta + 0.5 * omega * dt
        c, sn = np.cos(phi), np.sin(phi)
        F = np.eye(10)
        # d(omega)/dv and d(omega)/dr
        domega_dv, domega_dr = (r, v) if self.curvature else (0.0, 1.0)
        for row, trig in ((0, c), (1, sn)):
            dphi = -sn * s if row == 0 else c * s  # d(s·cos φ)/dφ or d(s·sin φ)/dφ
            F[row, HEADING] = dphi
            F[row, SPEED] = trig * dt + dphi * 0.5 * dt * domega_dv
            F[row, ACCELERATION] = trig * 0.5 * dt * dt
            F[row, TURN] = dphi * 0.5 * dt * domega_dr
        F[HEADING, SPEED] = dt * domega_dv
        F[HEADING, TURN] = dt * domega_dr
        F[SPEED, ACCELERATION] = dt
        out = x.copy()
        out[0] += s * c
        out[1] += s * sn
        out[HEADING] = wrap(theta + omega * dt)
        out[SPEED] = v + a * dt
        kf.x = out[:, None]
        kf.P = F @ kf.P @ F.T + np.diag(self.process) * max(dt, 1e-6)

    def update(self, kf: KalmanFilter, z: np.ndarray) -> None:
        """One measurement update with orientation correction: a box measured facing backwards turns the
        state by π, which reverses v and a (and κ, so that ω = v κ keeps its sign); the covariance follows."""
        theta = kf.x[HEADING, 0]
        if abs(wrap(z[HEADING] - theta)) > np.pi / 2:
            flip = np.ones(10)
            flip[[SPEED, ACCELERATION]] = -1.0
            if self.curvature:
                flip[TURN] = -1.0
            kf.x = kf.x * flip[:, None]
            kf.x[HEADING, 0] = wrap(theta + np.pi)
            kf.P = kf.P * np.outer(flip, flip)
        z = z.copy()
        z[HEADING] = kf.x[HEADING, 0] + wrap(z[HEADING] - kf.x[HEADING, 0])
        kf.update(z)
        kf.x[HEADING, 0] = wrap(kf.x[HEADING, 0])

    @staticmethod
    def velocity(x: np.ndarray) -> tuple[float, float]:
        """World-frame (vx, vy) [m/s] of a state (10,)."""
        return float(x[SPEED] * np.cos(x[HEADING])), float(x[SPEED] * np.sin(x[HEADING]))


_BOX_PROCESS = (0.5, 0.5, 0.1, 0.01, 0.01, 0.01, 0.05)  # x, y, z [m²/s], sizes [m²/s], θ [rad²/s]
CTRA = TurningModel("ctra", curvature=False, process=(*_BOX_PROCESS, 1.0, 4.0, 0.1), turn_variance=0.5)
"""Constant turn rate and acceleration; r = ω [rad/s]."""
BICYCLE = TurningModel("bicycle", curvature=True, process=(*_BOX_PROCESS, 1.0, 4.0, 1e-3), turn_variance=0.01)
"""Bicycle-like constant curvature and acceleration; r = κ [1/m]."""
