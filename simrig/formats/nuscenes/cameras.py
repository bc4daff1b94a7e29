"""nuScenes camera records of an export: each camera of the rig as a ``sensor`` and ``calibrated_sensor``, and a
key-frame ``sample_data`` per frame it took an image at, stamped with its true capture time.

A camera's ``sample_data`` has the ``timestamp`` [µs] of its capture (the frame's tick plus the camera's capture
offset when the scenario sets capture timing, :mod:`simrig.scenarios.timing_schema`; the tick otherwise) and its
own ``ego_pose``: the ego's true pose at that instant (moved from the tick at its velocity), as nuScenes records
one per sample_data. A camera slower than the frame rate has none at the frames it skips. Channels are the
camera's name in capitals, with ``CAM_`` in front unless it has it; ``calibrated_sensor`` holds the mount in the
ego frame (``translation`` [m], ``rotation`` the unit quaternion w, x, y, z taking the camera frame — x right, y
down, z forward — to the ego frame) and ``camera_intrinsic`` (K [px]). ``filename`` is empty: simrig writes no
images into an export.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from simrig.formats.export_input import ExportInput


def yaw_quaternion(yaw: float) -> list[float]:
    """Unit quaternion (w, x, y, z) of a rotation by ``yaw`` [rad] about +z."""
    return [float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2))]


def channel(camera: str) -> str:
    """The nuScenes channel of a simrig camera: its name in capitals, ``CAM_`` in front unless it starts so
    (``CAM_FRONT`` stays, ``left`` → ``CAM_LEFT``)."""
    name = camera.upper()
    return name if name.startswith("CAM_") else f"CAM_{name}"


def camera_tables(data: ExportInput, samples: list[str], ticks: list[int]) -> dict[str, list[dict]]:
    """``sensor``, ``calibrated_sensor``, ``sample_data`` and ``ego_pose`` records of every camera for the
    ``samples`` (tokens, one per frame of the ground truth) whose ticks are ``ticks`` [µs]."""
    truth = data.truth
    out: dict[str, list[dict]] = {"sensor": [], "calibrated_sensor": [], "sample_data": [], "ego_pose": []}
    offsets = truth.capture_offsets if truth.capture_offsets is not None else np.zeros(
        (len(samples), len(truth.rig.camera_names)))
    for c, name in enumerate(truth.rig.camera_names):
        camera = truth.rig.camera(name)
        mount = camera.ego_from_camera()
        w, x, y, z = np.roll(Rotation.from_matrix(mount[:3, :3]).as_quat(), 1)
        out["sensor"].append({"token": f"sensor-{name}", "channel": channel(name), "modality": "camera"})
        out["calibrated_sensor"].append({
            "token": f"calibrated-{name}", "sensor_token": f"sensor-{name}",
            "translation": [float(v) for v in mount[:3, 3]], "rotation": [float(w), float(x), float(y), float(z)],
            "camera_intrinsic": camera.intrinsics.tolist()})
        fired = np.flatnonzero(np.isfinite(offsets[:, c]))
        tokens = [f"{name}-{samples[k]}" for k in fired]
        for j, k in enumerate(fired):
            offset = float(offsets[k, c])
            time = ticks[k] + int(round(offset * 1e6))
            ego = truth.egos[k].moved(offset)
            out["ego_pose"].append({"token": f"ego-{tokens[j]}", "timestamp": time,
                                    "translation": [ego.x, ego.y, ego.z],
                                    "rotation": yaw_quaternion(ego.yaw)})
            out["sample_data"].append({
                "token": tokens[j], "sample_token": samples[k], "ego_pose_token": f"ego-{tokens[j]}",
                "calibrated_sensor_token": f"calibrated-{name}", "timestamp": time, "fileformat": "jpg",
                "is_key_frame": True, "height": camera.height, "width": camera.width, "filename": "",
                "prev": tokens[j - 1] if j else "", "next": tokens[j + 1] if j + 1 < len(tokens) else ""})
    return out
