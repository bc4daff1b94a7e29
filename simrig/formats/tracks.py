"""Tracks in any of the formats ``simrig score`` reads: simrig Parquet (:mod:`simrig.dataset.tracks_file`),
MOTChallenge text (:mod:`simrig.formats.motchallenge.tracks`), KITTI tracking labels
(:mod:`simrig.formats.kitti.tracks`) and nuScenes tracking-results JSON (:mod:`simrig.formats.nuscenes.tracks`),
named or detected from the path:

- a ``.json`` file → nuScenes; a ``.parquet`` file, or a folder with ``tracks3d.parquet`` / ``tracks2d.parquet``
  → simrig;
- a folder with ``trackers/mot_challenge`` → MOTChallenge; with a camera sub-folder → KITTI (the exports'
  layouts);
- a ``.txt`` file, or a folder of them: commas on the first line → MOTChallenge, else KITTI.

Whatever the format, the rows then pass the same checks as simrig's own files.
"""

from __future__ import annotations

from pathlib import Path

from simrig.dataset.ground_truth import project_tracks, relative_to_true_ego
from simrig.dataset.run_folder import SCORES_DIR, TRACKS_DIR
from simrig.dataset.tracks_file import TRACKS2D_FILE, TRACKS3D_FILE, TrackRows, TrackSet, read_tracks, tracks_in_memory
from simrig.errors import TracksError
from simrig.formats import OUTSIDE_FORMATS
from simrig.formats.kitti.tracks import read_kitti
from simrig.formats.motchallenge.tracks import read_motchallenge
from simrig.formats.nuscenes.samples import sample_tokens, scene_of_frame
from simrig.formats.nuscenes.tracks import read_nuscenes
from simrig.reading import check_regular, open_regular

FORMATS = ("simrig", *OUTSIDE_FORMATS)


def not_tracks(path: Path) -> str | None:
    """What ``path`` is when it is a part of a run folder other than tracks, said with where the tracks are (a
    score report, a folder of several trackers' tracks); None otherwise."""
    if path.is_file() and path.parent.parent.name == SCORES_DIR:
        tracks = path.parent.parent.parent / TRACKS_DIR / path.parent.name
        return (f"{path} is a score report of a run folder, not tracks; the tracks it scored are in {tracks}")
    if path.is_dir() and not any((path / name).exists() for name in (TRACKS3D_FILE, TRACKS2D_FILE)):
        labels = sorted(child.name for child in path.iterdir()
                        if child.is_dir() and any((child / name).is_file() for name in (TRACKS3D_FILE, TRACKS2D_FILE)))
        if labels:
            shown = ", ".join(labels[:8]) + (", …" if len(labels) > 8 else "")
            return (f"{path} holds the tracks of {len(labels)} trackers ({shown}); name one, e.g. "
                    f"{path / labels[0]}")
    return None


def detect_format(path: Path, cameras: tuple[str, ...]) -> str:
    """The format of the tracks at ``path`` (see the module's rules); an error when none fits."""
    wrong = not_tracks(path)
    if wrong is not None:
        raise TracksError(wrong)
    if path.is_file():
        if path.suffix == ".json":
            return "nuscenes"
        if path.suffix == ".txt":
            return _sniff(path)
        return "simrig"
    if not path.is_dir():
        raise TracksError(f"tracks {str(path)!r} does not exist")
    if any((path / name).exists() for name in (TRACKS3D_FILE, TRACKS2D_FILE)):
        return "simrig"
    if (path / "trackers" / "mot_challenge").is_dir() or (path / "data").is_dir():
        return "motchallenge"
    if any((path / camera).is_dir() for camera in cameras):
        return "kitti"
    texts = sorted(path.glob("*.txt"))
    if texts:
        return _sniff(texts[0])
    raise TracksError(f"{path}: no tracks in a known layout (simrig Parquet, MOTChallenge, KITTI or nuScenes "
                      "files); name the format with --format")


def _sniff(file: Path) -> str:
    try:
        with open_regular(file, "tracks file", TracksError) as stream:
            first = next((line.decode("utf-8") for line in stream if line.strip()), "")
    except (OSError, UnicodeDecodeError) as error:
        raise TracksError(f"{file}: cannot be read as text ({error})") from None
    return "motchallenge" if "," in first else "kitti"


def read_tracks_as(path: Path | str, fmt: str | None = None, *, frame_count: int, cameras: tuple[str, ...],
                   tokens: dict[str, int] | None = None, classes: str = "each",
                   scenes=None) -> TrackSet:
    """Read and validate the tracks at ``path`` in format ``fmt`` (detected when ``None``) against a dataset of
    ``frame_count`` frames seen by ``cameras``; ``tokens``: its nuScenes sample token → frame; ``classes``: the
    evaluation's class setting (class-less MOTChallenge files need ``any``); ``scenes``: ``(F,)`` scene index
    per frame of a dataset made of several nuScenes scenes (a track id names one track per scene), or ``None``."""
    path = Path(path)
    if fmt is not None and fmt not in FORMATS:
        raise TracksError(f"--format {fmt!r}: tracks formats are {', '.join(FORMATS)}")
    if not path.exists():
        raise TracksError(f"tracks {str(path)!r} does not exist")
    if not path.is_dir():
        check_regular(path, "tracks file", TracksError)  # a FIFO or a device is named as such
    fmt = fmt or detect_format(path, cameras)
    if fmt == "simrig":
        return read_tracks(path, frame_count=frame_count, cameras=cameras)
    if fmt == "motchallenge":
        tables = read_motchallenge(path, frame_count=frame_count, cameras=cameras, classes=classes)
    elif fmt == "kitti":
        tables = read_kitti(path, frame_count=frame_count, cameras=cameras)
    else:
        if not path.is_file():
            raise TracksError(f"{path}: nuScenes tracks are one results .json file")
        tables = read_nuscenes(path, tokens=tokens or {}, scenes=scenes)
    return tracks_in_memory(tables, frame_count=frame_count, cameras=cameras, source=f"{path} ({fmt})")


def dataset_tracks(dataset, path: Path | str, fmt: str | None = None) -> tuple[TrackRows | None, TrackRows]:
    """A tracker's rows at ``path`` (any format) for drawing on ``dataset``: (3D rows or ``None``, 2D rows — its
    own, or its 3D boxes projected into the cameras as the scorer projects them). Class-less MOTChallenge files
    are read as class-agnostic."""
    truth = dataset.ground_truth
    tracks = read_tracks_as(path, fmt, frame_count=len(truth.frames), cameras=truth.rig.camera_names,
                            tokens=sample_tokens(dataset), classes="any", scenes=scene_of_frame(dataset))
    if tracks.tracks3d is None or (tracks.tracks2d is not None and len(tracks.tracks2d)):
        return tracks.tracks3d, tracks.tracks2d
    tracks3d = relative_to_true_ego(truth, tracks.tracks3d)  # drawn where the scorer sees them
    return tracks3d, project_tracks(truth, tracks3d)
