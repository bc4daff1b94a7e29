"""Images to trackers: a dataset generated with images hands each frame's PNG paths to the tracker in
``SensorFrame.images``; ``simrig track --images`` refuses a dataset without them; the viewer logs the images."""

import numpy as np
import pytest
from PIL import Image
from simrig.scenarios import load_scenario

from simrig.cli import main
from simrig.pipeline.generate import generate
from simrig.pipeline.track import run_tracker


class ImageReader:
    """A tracker that opens every image it is given (and tracks nothing)."""

    def reset(self, *, rig, seed=None):
        self.rig, self.seen = rig, []

    def step(self, frame):
        sizes = {name: Image.open(path).size for name, path in frame.images.items()}
        self.seen.append((frame.frame, sizes))
        return []


@pytest.fixture(scope="module")
def tiny_with_images(tmp_path_factory):
    folder = tmp_path_factory.mktemp("images")
    (folder / "tiny.toml").write_text('extends = "highway_surround6"\nframes = 3\n'
                                      "[traffic]\nvehicles = 4\nwindow_radius_m = 80.0\nspawn_min_distance_m = 40.0\n")
    return generate(load_scenario(folder / "tiny.toml"), seed=0, out=folder / "dataset", images=True).path


def test_each_frame_gives_every_cameras_image_path(tiny_with_images, tmp_path, capsys):
    from simrig.dataset import Dataset

    dataset = Dataset.open(tiny_with_images)
    tracker = ImageReader()
    run_tracker(dataset, tracker)
    assert [frame for frame, _ in tracker.seen] == list(range(3))
    for _, sizes in tracker.seen:
        assert sizes == {camera.name: (camera.width, camera.height) for camera in dataset.rig.cameras}
    # the PNG at the path is the frame's image: frame 0 and frame 2 differ (the traffic moves)
    first, last = (next(f for i, f in enumerate(dataset.sensor_frames()) if i == k) for k in (0, 2))
    camera = dataset.rig.camera_names[0]
    assert first.images[camera].endswith(f"images/{camera}/000000.png")
    assert not np.array_equal(np.asarray(Image.open(first.images[camera])), np.asarray(Image.open(last.images[camera])))

    assert main(["track", str(tiny_with_images), "--tracker", "sort", "--images", "--out", str(tmp_path / "t")]) == 0


def test_track_images_refuses_a_dataset_without_images(small_dataset, tmp_path, capsys):
    assert all(frame.images == {} for frame in small_dataset.sensor_frames())
    assert main(["track", str(small_dataset.path), "--images", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert err == f"simrig: error: --images: {small_dataset.path} has no images (generate it with --images)\n"


def test_viewer_logs_each_cameras_image(tiny_with_images, tmp_path):
    rerun_chunk = pytest.importorskip("rerun.chunk")
    assert main(["view", str(tiny_with_images), "--save", str(tmp_path / "v.rrd")]) == 0
    rows = {}
    for chunk in rerun_chunk.RrdReader(tmp_path / "v.rrd").stream().to_chunks():
        rows[chunk.entity_path] = rows.get(chunk.entity_path, 0) + chunk.num_rows
    from simrig.dataset import Dataset

    for camera in Dataset.open(tiny_with_images).rig.camera_names:
        assert rows[f"/cameras/{camera}/image"] == 3
        assert f"/cameras/{camera}/frame" not in rows
