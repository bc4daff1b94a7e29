"""``simrig render --tracks``: a tracker's box is drawn, in its track's colour, where the file puts it."""

import numpy as np
from PIL import Image

from simrig.cli import main
from simrig.figures import mosaic


def test_render_draws_the_tracks_of_a_file(small_dataset, tmp_path, monkeypatch):
    # the camera images themselves are not under test: plain grey keeps the render fast
    monkeypatch.setattr(mosaic, "_camera_images", lambda dataset, state: {
        c.name: np.full((c.height, c.width, 3), 128, np.uint8) for c in dataset.rig.cameras})
    camera = small_dataset.rig.cameras[1]
    tracks = tmp_path / f"{camera.name}-car.txt"
    tracks.write_text(f"2,3,{camera.width * 0.3},{camera.height * 0.3},{camera.width * 0.4},{camera.height * 0.4},"
                      "0.9,-1,-1,-1\n")
    assert main(["render", str(small_dataset.path), "--frame", "1", "--out", str(tmp_path / "plain.png")]) == 0
    assert main(["render", str(small_dataset.path), "--frame", "1", "--tracks", str(tracks),
                 "--out", str(tmp_path / "tracked.png")]) == 0
    plain = np.asarray(Image.open(tmp_path / "plain.png").convert("RGB")).astype(int)
    tracked = np.asarray(Image.open(tmp_path / "tracked.png").convert("RGB")).astype(int)
    assert plain.shape == tracked.shape
    changed = np.any(plain != tracked, axis=2)
    colour = np.array(mosaic.track_colour(3)) * 255
    in_colour = np.all(np.abs(tracked - colour) < 20, axis=2)
    assert (changed & in_colour).sum() > 50  # the dotted outline, in track 3's colour
