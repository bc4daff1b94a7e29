"""Camera rigs: pinhole cameras mounted on the ego vehicle, built from a scenario's ``[rig]`` table.

Presets (angles are the optical axis' yaw in the ego frame, CCW from +x, in degrees):

* ``surround6`` — nuScenes-like: CAM_FRONT 0, CAM_FRONT_LEFT 55, CAM_BACK_LEFT 110, CAM_BACK 180,
  CAM_BACK_RIGHT −110, CAM_FRONT_RIGHT −55; 1600×900 px. Neighbours 55° apart get a field of view of
  55° + overlap; the back camera, 70° from its neighbours, gets 85° + overlap so that it overlaps them by
  the same angle (65° and 95° at the default 10° overlap; nuScenes: about 70° and 110°).
* ``stereo`` — KITTI-like: ``left`` and ``right`` both facing forward, ``baseline_m`` apart along the ego's
  y axis (left at +b/2), 1242×375 px, 81.2° field of view (f ≈ 721 px as KITTI's).
* ``ring`` — N cameras at the ego origin, evenly spaced in yaw starting at 0, named CAM_0 … CAM_{N−1};
  field of view 360°/N + overlap.
* ``custom`` — the scenario lists every camera.

Focal lengths follow from the horizontal field of view, fx = (W/2) / tan(hfov/2); pixels are square
(fy = fx) and the principal point is the image centre.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

from .types import Camera, Rig

if TYPE_CHECKING:
    from simrig.scenarios.schema import RigConfig

SURROUND6_LAYOUT: tuple[tuple[str, float, float, float], ...] = (
    # name, yaw [deg], x [m], y [m] on the ego (origin: centre of the footprint)
    ("CAM_FRONT", 0.0, 1.5, 0.0),
    ("CAM_FRONT_LEFT", 55.0, 1.3, 0.5),
    ("CAM_BACK_LEFT", 110.0, -0.4, 0.5),
    ("CAM_BACK", 180.0, -1.4, 0.0),
    ("CAM_BACK_RIGHT", -110.0, -0.4, -0.5),
    ("CAM_FRONT_RIGHT", -55.0, 1.3, -0.5),
)
SURROUND6_SIZE_PX = (1600, 900)
STEREO_SIZE_PX = (1242, 375)


def pinhole(
    name: str,
    *,
    hfov_deg: float,
    width: int,
    height: int,
    position: tuple[float, float, float],
    yaw_deg: float,
    pitch_deg: float = 0.0,
) -> Camera:
    """A square-pixel camera with its principal point at the image centre.

    >>> cam = pinhole("c", hfov_deg=90.0, width=200, height=100, position=(0.0, 0.0, 1.0), yaw_deg=0.0)
    >>> round(cam.fx, 6), cam.cx, cam.cy
    (100.0, 100.0, 50.0)
    """
    focal = (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
    return Camera(
        name=name,
        width=width,
        height=height,
        fx=focal,
        fy=focal,
        cx=width / 2.0,
        cy=height / 2.0,
        position=position,
        yaw=math.radians(yaw_deg),
        pitch=math.radians(pitch_deg),
    )


def _size(config: RigConfig, default: tuple[int, int]) -> tuple[int, int]:
    return (config.image_width_px or default[0], config.image_height_px or default[1])


def _surround6(config: RigConfig) -> Rig:
    width, height = _size(config, SURROUND6_SIZE_PX)
    side_fov = 55.0 + config.overlap_deg
    back_fov = 85.0 + config.overlap_deg
    cameras = tuple(
        pinhole(
            name,
            hfov_deg=back_fov if name == "CAM_BACK" else side_fov,
            width=width,
            height=height,
            position=(x, y, config.mount_height_m),
            yaw_deg=yaw,
        )
        for name, yaw, x, y in SURROUND6_LAYOUT
    )
    return Rig("surround6", cameras)


def _stereo(config: RigConfig) -> Rig:
    width, height = _size(config, STEREO_SIZE_PX)
    half = config.baseline_m / 2.0
    cameras = tuple(
        pinhole(
            name,
            hfov_deg=config.hfov_deg,
            width=width,
            height=height,
            position=(0.0, y, config.mount_height_m),
            yaw_deg=0.0,
        )
        for name, y in (("left", half), ("right", -half))
    )
    return Rig("stereo", cameras)


def _ring(config: RigConfig) -> Rig:
    width, height = _size(config, SURROUND6_SIZE_PX)
    count = config.cameras_count
    spacing = 360.0 / count
    cameras = tuple(
        pinhole(
            f"CAM_{index}",
            hfov_deg=spacing + config.overlap_deg,
            width=width,
            height=height,
            position=(0.0, 0.0, config.mount_height_m),
            yaw_deg=index * spacing,
        )
        for index in range(count)
    )
    return Rig(f"ring{count}", cameras)


def _custom(config: RigConfig) -> Rig:
    cameras = tuple(
        pinhole(
            camera.name,
            hfov_deg=camera.hfov_deg,
            width=camera.width_px,
            height=camera.height_px,
            position=(camera.x_m, camera.y_m, camera.z_m),
            yaw_deg=camera.yaw_deg,
            pitch_deg=camera.pitch_deg,
        )
        for camera in config.cameras
    )
    return Rig("custom", cameras)


_BUILDERS = {"surround6": _surround6, "stereo": _stereo, "ring": _ring, "custom": _custom}


def build_rig(config: RigConfig) -> Rig:
    """The :class:`~simrig.types.Rig` a validated ``[rig]`` table describes."""
    try:
        builder = _BUILDERS[config.preset]
    except KeyError:
        raise ValueError(f"rig.preset: unknown preset {config.preset!r}; known: {', '.join(_BUILDERS)}") from None
    return builder(config)


def scaled_rig(rig: Rig, scale: float) -> Rig:
    """The same cameras at ``scale`` × the resolution (same poses and fields of view); the visibility
    render and the silhouettes use it. Sizes are rounded to whole pixels and the intrinsics follow the
    actual size ratio, so a pixel ray is unchanged.

    >>> cam = pinhole("c", hfov_deg=90.0, width=1600, height=900, position=(0.0, 0.0, 1.0), yaw_deg=0.0)
    >>> small = scaled_rig(Rig("r", (cam,)), 0.5).cameras[0]
    >>> small.width, small.height, round(small.fx, 9), small.cx
    (800, 450, 400.0, 400.0)
    """
    if not 0.0 < scale <= 1.0:
        raise ValueError(f"scale: must be in (0, 1], got {scale}")
    cameras = []
    for camera in rig.cameras:
        width, height = max(1, round(camera.width * scale)), max(1, round(camera.height * scale))
        sx, sy = width / camera.width, height / camera.height
        cameras.append(dataclasses.replace(
            camera, width=width, height=height, fx=camera.fx * sx, fy=camera.fy * sy, cx=camera.cx * sx,
            cy=camera.cy * sy,
        ))
    return Rig(rig.name, tuple(cameras))


def rig_to_dict(rig: Rig) -> dict:
    """A JSON-ready description of ``rig``: per camera its intrinsics, mount and 4×4 ego-from-camera matrix."""
    return {
        "name": rig.name,
        "frames": {"ego": "x forward, y left, z up [m]", "camera": "OpenCV: x right, y down, z forward [m]"},
        "cameras": [
            {
                "name": camera.name,
                "width": camera.width,
                "height": camera.height,
                "fx": camera.fx,
                "fy": camera.fy,
                "cx": camera.cx,
                "cy": camera.cy,
                "position": list(camera.position),
                "yaw": camera.yaw,
                "pitch": camera.pitch,
                "roll": camera.roll,
                "near": camera.near,
                "intrinsics": camera.intrinsics.tolist(),
                "ego_from_camera": camera.ego_from_camera().tolist(),
            }
            for camera in rig.cameras
        ],
    }


def rig_from_dict(data: dict) -> Rig:
    """Inverse of :func:`rig_to_dict` (the derived matrices are recomputed, not read)."""
    cameras = tuple(
        Camera(
            name=entry["name"],
            width=int(entry["width"]),
            height=int(entry["height"]),
            fx=float(entry["fx"]),
            fy=float(entry["fy"]),
            cx=float(entry["cx"]),
            cy=float(entry["cy"]),
            position=tuple(float(v) for v in entry["position"]),
            yaw=float(entry["yaw"]),
            pitch=float(entry["pitch"]),
            roll=float(entry["roll"]),
            near=float(entry["near"]),
        )
        for entry in data["cameras"]
    )
    return Rig(data["name"], cameras)
