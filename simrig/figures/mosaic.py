"""``simrig render DIR --frame N``: one PNG with every camera's image, ground-truth and detection boxes
coloured by identity, and a bird's-eye panel of the same frame.

Camera images come from the dataset's ``images/`` when it was generated with ``--images``; otherwise they
are rendered now from the stored ground truth and road (same scene, same pixels as ``--images`` gives).
Solid boxes are ground truth, dashed boxes detections (coloured by the actor that caused them; red for
false positives). With ``--tracks`` (a tracker's output in any format ``simrig score`` reads), dotted boxes
labelled ``T<id>`` are the tracker's — each track id in its own stable colour — in every camera (its own 2D
boxes, or its 3D boxes projected as the scorer projects them) and, for a 3D tracker, in the bird's-eye panel.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow.compute as pc  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.patches import Polygon, Rectangle  # noqa: E402

from simrig.dataset import Dataset  # noqa: E402
from simrig.dataset.outputs import save_figure  # noqa: E402
from simrig.errors import DatasetError  # noqa: E402
from simrig.geometry import box_corners  # noqa: E402
from simrig.road import dash_segments  # noqa: E402
from simrig.types import GroundTruthFrame  # noqa: E402

SURROUND_LAYOUT = (("CAM_FRONT_LEFT", "CAM_FRONT", "CAM_FRONT_RIGHT"), ("CAM_BACK_LEFT", "CAM_BACK", "CAM_BACK_RIGHT"))
"""nuScenes' usual arrangement of the six surround images."""
BEV_RANGE_M = 60.0
"""[m] half side of the bird's-eye panel around the ego."""
CLUTTER_COLOUR = (0.9, 0.1, 0.1)


def identity_colour(actor_id: int) -> tuple[float, float, float]:
    """A stable colour per actor id (tab20)."""
    return plt.cm.tab20(int(actor_id) % 20)[:3]


def track_colour(track_id: int) -> tuple[float, float, float]:
    """A stable colour per track id (tab10, so that a track and the actor it follows rarely look alike)."""
    return plt.cm.tab10(int(track_id) % 10)[:3]


def _frame_tracks(dataset: Dataset, tracks, frame: int):
    """(per camera: [(pixel box, track id)], [(world box, track id)]) of a tracker's rows at ``frame``."""
    if tracks is None:
        return {}, []
    from simrig.formats.tracks import dataset_tracks

    rows3d, rows2d = dataset_tracks(dataset, tracks)
    per_camera: dict[str, list] = {}
    if rows2d is not None:
        for k in np.nonzero(rows2d.frame == frame)[0]:
            per_camera.setdefault(str(rows2d.camera[k]), []).append((rows2d.boxes[k], int(rows2d.track_id[k])))
    world = [] if rows3d is None else [(rows3d.boxes[k], int(rows3d.track_id[k]))
                                       for k in np.nonzero(rows3d.frame == frame)[0]]
    return per_camera, world


def _layout(names: tuple[str, ...]) -> list[list[str]]:
    if set(names) == {name for row in SURROUND_LAYOUT for name in row}:
        return [list(row) for row in SURROUND_LAYOUT]
    columns = 1 if len(names) <= 2 else min(3, len(names))  # a stereo pair: one above the other
    return [list(names[i:i + columns]) for i in range(0, len(names), columns)]


def _camera_images(dataset: Dataset, state: GroundTruthFrame) -> dict[str, np.ndarray]:
    images = dataset.path / "images"
    if images.is_dir():
        from PIL import Image

        names = dataset.rig.camera_names
        return {name: np.asarray(Image.open(images / name / f"{state.frame:06d}.png")) for name in names}
    if not dataset.has_3d:  # imported 2D boxes: no world to render; a blank frame of the camera's size
        return {camera.name: np.full((camera.height, camera.width, 3), 235, dtype=np.uint8)
                for camera in dataset.rig.cameras}
    from simrig.render.scene import RigScene

    scene = RigScene(dataset.road_markings())
    scene.set_frame(state.ego, state.classes, state.boxes)
    return {camera.name: scene.colour(camera, dataset.rig, state.ego) for camera in dataset.rig.cameras}


def _detections(dataset: Dataset, frame: int) -> dict[str, list[tuple[np.ndarray, np.ndarray, int]]]:
    """Per camera: (pixel box, world box, actor id or −1) of every detection of ``frame``."""
    detections = dataset.table("detections").filter(pc.equal(pc.field("frame"), frame)).to_pandas()
    truth = dataset.table("sensor_truth").filter(pc.equal(pc.field("frame"), frame)).to_pandas()
    truth = truth[truth.detection >= 0]
    owner = {(row.camera, row.detection): row.actor_id for row in truth.itertuples()}
    out: dict[str, list] = {}
    for row in detections.itertuples():
        box2d = np.array([row.x1, row.y1, row.x2, row.y2])
        box3d = np.array([row.x, row.y, row.z, row.length, row.width, row.height, row.yaw])
        out.setdefault(row.camera, []).append((box2d, box3d, int(owner.get((row.camera, row.index), -1))))
    return out


def _box_patch(box: np.ndarray, colour, dashed: bool) -> Rectangle:
    x1, y1, x2, y2 = box
    return Rectangle((x1, y1), x2 - x1, y2 - y1, fill=False, edgecolor=colour, linewidth=1.6 if not dashed else 1.2,
                     linestyle="--" if dashed else "-")


def _draw_bev(axis, dataset: Dataset, state: GroundTruthFrame, detections, tracks3d=()) -> None:
    ego = state.ego
    rotation = np.array([[np.cos(-ego.yaw), -np.sin(-ego.yaw)], [np.sin(-ego.yaw), np.cos(-ego.yaw)]])

    def to_ego(points: np.ndarray) -> np.ndarray:
        return (points - [ego.x, ego.y]) @ rotation.T

    markings = dataset.road_markings()
    if markings is not None:
        segments = [to_ego(dash_segments(line, dashed).reshape(-1, 2)).reshape(-1, 2, 2)
                    for line, dashed in zip(markings.lines, markings.dashed, strict=True)]
        segments = np.concatenate(segments) if segments else np.zeros((0, 2, 2))
        a, b = segments[:, 0], segments[:, 1]
        step = b - a
        t = np.clip(-np.einsum("ij,ij->i", a, step) / np.maximum(np.einsum("ij,ij->i", step, step), 1e-12), 0, 1)
        near = np.abs(a + t[:, None] * step).max(axis=1) < 1.5 * BEV_RANGE_M  # closest point to the ego
        axis.add_collection(LineCollection(segments[near], colors="0.7", linewidths=0.8))
    for actor_id, corners in zip(state.actor_ids, box_corners(state.boxes)[:, :4, :2], strict=True):
        axis.add_patch(Polygon(to_ego(corners), closed=True, facecolor=identity_colour(actor_id), alpha=0.55,
                               edgecolor=identity_colour(actor_id)))
        centre = to_ego(corners.mean(axis=0, keepdims=True))[0]
        if np.abs(centre).max() < BEV_RANGE_M:
            axis.text(*centre, str(actor_id), fontsize=6, ha="center", va="center")
    for items in detections.values():
        for _, box3d, actor_id in items:
            colour = CLUTTER_COLOUR if actor_id < 0 else identity_colour(actor_id)
            corners = to_ego(box_corners(box3d[None])[0, :4, :2])
            axis.add_patch(Polygon(corners, closed=True, fill=False, edgecolor=colour, linestyle="--", linewidth=0.9))
    for box3d, track_id in tracks3d:
        corners = to_ego(box_corners(box3d[None, :7])[0, :4, :2])
        axis.add_patch(Polygon(corners, closed=True, fill=False, edgecolor=track_colour(track_id), linestyle=":",
                               linewidth=1.6))
        centre = corners.mean(axis=0)
        if np.abs(centre).max() < BEV_RANGE_M:
            axis.text(centre[0], centre[1] + 2.5, f"T{track_id}", fontsize=6, ha="center", color=track_colour(track_id))
    axis.add_patch(Rectangle((-2.3, -0.95), 4.6, 1.9, facecolor="black"))
    axis.set_xlim(-BEV_RANGE_M, BEV_RANGE_M)
    axis.set_ylim(-BEV_RANGE_M, BEV_RANGE_M)
    axis.set_aspect("equal")
    axis.set_title("bird's-eye (ego frame, x forward, y left) [m]", fontsize=9)
    axis.tick_params(labelsize=7)


def _capture_offsets(dataset: Dataset, frame: int) -> dict[str, float] | None:
    """Per camera, its capture time minus the frame's tick [s] (NaN: it took no image), for a dataset with capture
    timing; ``None`` otherwise."""
    truth = dataset.ground_truth
    if truth.capture_offsets is None:
        return None
    row = truth.capture_offsets[int(np.searchsorted(truth.frames, frame))]
    return dict(zip(truth.rig.camera_names, row.tolist(), strict=True))


def _capture_note(offsets: dict[str, float] | None, name: str) -> str:
    """`` (+25 ms)`` after a camera's name when it fired after the tick; `` (no image)`` when it skipped the frame;
    nothing on a synchronous rig."""
    if offsets is None:
        return ""
    offset = offsets[name]
    return " (no image)" if not np.isfinite(offset) else f" ({1000 * offset:+.0f} ms)"


def render_mosaic(dataset_path: Path | str, frame: int, out: Path | str, tracks: Path | str | None = None) -> Path:
    """Write the mosaic PNG of ``frame`` of the dataset at ``dataset_path`` to ``out`` (with ``tracks``, a
    tracker's output in any format ``simrig score`` reads, drawn too); returns ``out``."""
    dataset = Dataset.open(dataset_path)
    if not 0 <= frame < dataset.frame_count:
        raise DatasetError(f"--frame: {frame} is outside the dataset's frames 0 … {dataset.frame_count - 1}")
    state = next(f for i, f in enumerate(dataset.ground_truth_frames()) if i == frame)
    images = _camera_images(dataset, state)
    detections = _detections(dataset, frame)
    tracks2d, tracks3d = _frame_tracks(dataset, tracks, frame)
    offsets = _capture_offsets(dataset, frame)
    # an imported dataset may have no cameras (3D only) or no 3D ground truth (2D only): draw what it has
    layout = _layout(dataset.rig.camera_names) if dataset.has_2d else []
    rows, columns = max(len(layout), 1), max((len(row) for row in layout), default=0)
    aspect = dataset.rig.cameras[0].height / dataset.rig.cameras[0].width if columns else 1.0
    panel = 4.2 if columns > 1 else 8.0  # [in] width of one camera image
    height = max(5.0, panel * aspect * rows + 0.8)
    bev = 1 if dataset.has_3d else 0
    figure = plt.figure(figsize=(panel * columns + height * bev, height), dpi=110)
    grid = figure.add_gridspec(rows, columns + bev, width_ratios=[panel] * columns + [height] * bev)
    for r, row in enumerate(layout):
        for c, name in enumerate(row):
            axis = figure.add_subplot(grid[r, c])
            axis.imshow(images[name])
            truth = state.cameras[name]
            for actor_id, box, in_view in zip(state.actor_ids, truth.boxes, truth.in_view, strict=True):
                if in_view:
                    axis.add_patch(_box_patch(box, identity_colour(actor_id), dashed=False))
            for box2d, _, actor_id in detections.get(name, []):
                colour = CLUTTER_COLOUR if actor_id < 0 else identity_colour(actor_id)
                axis.add_patch(_box_patch(box2d, colour, dashed=True))
            for box2d, track_id in tracks2d.get(name, []):
                x1, y1, x2, y2 = box2d
                axis.add_patch(Rectangle((x1, y1), x2 - x1, y2 - y1, fill=False, edgecolor=track_colour(track_id),
                                         linewidth=1.8, linestyle=":"))
                axis.text(x1, y1 - 3, f"T{track_id}", fontsize=5, color=track_colour(track_id), va="bottom")
            tracked = f", {len(tracks2d.get(name, []))} tracks" if tracks is not None else ""
            axis.set_title(f"{name}{_capture_note(offsets, name)}: {int(truth.in_view.sum())} in view, "
                           f"{len(detections.get(name, []))} detections{tracked}", fontsize=8)
            axis.set_axis_off()
    if bev:
        _draw_bev(figure.add_subplot(grid[:, columns]), dataset, state, detections, tracks3d)
    scenario = dataset.scenario["name"]
    figure.suptitle(f"{scenario}, seed {dataset.seed}, frame {frame} (t = {state.timestamp:.1f} s); solid: ground "
                    "truth, dashed: detections (red: false positives)"
                    + (", dotted: tracks (T<id>)" if tracks is not None else ""), fontsize=10)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    save_figure(figure, out, bbox_inches="tight")
    plt.close(figure)
    return out
