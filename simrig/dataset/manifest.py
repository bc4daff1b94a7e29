"""The dataset manifest: what a folder holds, how it was made, and whether it is complete.

``manifest.json`` is the last file written into a dataset folder, and its ``complete`` flag is its last
key. A folder without a manifest whose ``complete`` is ``true`` is never read as a dataset.

The manifest guards itself and the files: ``manifest_sha256`` is the SHA-256 of its own content (every key but
that one and ``complete``, as canonical JSON), checked whenever a dataset is opened, and every file entry holds
the file's SHA-256, checked whenever the file is read. Every file entry is a plain name in the dataset folder
(a manifest cannot make simrig read outside it).
"""

from __future__ import annotations

import hashlib
import json
import platform
import re
from pathlib import Path

from simrig.scenarios import MAX_FRAMES
from simrig.version import __version__

from ..errors import DatasetError
from ..reading import open_regular, read_capped, read_json
from .outputs import write_text_atomic

MANIFEST_NAME = "manifest.json"
FORMAT_NAME = "simrig-dataset"
FORMAT_VERSION = 2
"""2: visibility, detections, sensor_truth and frames tables, road.json, optional images."""
IMAGES_FOLDER = "images"
_VERSIONED_PACKAGES = (
    "simrig", "highway-env", "gymnasium", "numpy", "scipy", "pyarrow", "pydantic", "pyrender", "trimesh", "pillow",
)


def file_sha256(path: Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open_regular(path, "dataset file", DatasetError) as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def folder_digest(folder: Path) -> dict:
    """``{"folder", "files", "sha256"}`` of every file under ``folder``: one SHA-256 over the sorted relative
    paths and each file's own SHA-256 (so a renamed, missing or changed file changes it)."""
    digest = hashlib.sha256()
    paths = sorted(path for path in folder.rglob("*") if path.is_file())
    for path in paths:
        digest.update(f"{path.relative_to(folder).as_posix()}\0{file_sha256(path)}\n".encode())
    return {"folder": folder.name, "files": len(paths), "sha256": digest.hexdigest()}


def package_versions() -> dict[str, str]:
    """Versions of the packages that shape a dataset's bytes (and Python's)."""
    from importlib import metadata  # writing a manifest needs it, reading one does not

    versions = {"python": platform.python_version()}
    for name in _VERSIONED_PACKAGES:
        if name == "simrig":  # this package's own version, whatever its distribution is called
            versions[name] = __version__
            continue
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


_SELF_KEYS = ("manifest_sha256", "complete")
_SHA256 = re.compile(r"[0-9a-f]{64}")


def manifest_digest(manifest: dict) -> str:
    """SHA-256 of the manifest's own content: canonical JSON of every key but ``manifest_sha256``/``complete``."""
    content = {key: value for key, value in manifest.items() if key not in _SELF_KEYS}
    text = json.dumps(content, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _plain_name(name: object) -> bool:
    """A file name with no folder part: it cannot point outside the dataset folder."""
    return (isinstance(name, str) and name not in ("", ".", "..") and "/" not in name and "\\" not in name
            and "\0" not in name)


MAX_FRAME_RATE_HZ = 1000.0
"""[Hz] the highest frame rate a manifest may state (a scenario allows 100 Hz; imported sequences run slower)."""


def _check_manifest(path: Path, manifest: dict) -> None:
    """Refuse a complete manifest that was edited or that points outside its folder (one line naming the key)."""
    files = manifest.get("files")
    if not isinstance(files, dict) or not files:
        raise DatasetError(f"{path}: manifest key 'files' is missing or not a table")
    for name, entry in files.items():
        if not isinstance(entry, dict) or not _plain_name(entry.get("file")):
            raise DatasetError(f"{path}: manifest files.{name}.file must be a plain file name in the dataset folder, "
                               f"got {entry.get('file') if isinstance(entry, dict) else entry!r}")
        if not isinstance(entry.get("sha256"), str) or not _SHA256.fullmatch(entry["sha256"]):
            raise DatasetError(f"{path}: manifest files.{name}.sha256 is not a SHA-256")
    images = manifest.get("images")
    if images is not None and (not isinstance(images, dict) or not _plain_name(images.get("folder"))):
        raise DatasetError(f"{path}: manifest images.folder must be a plain folder name in the dataset folder")
    for key, minimum in (("frames", 1), ("seed", 0)):
        value = manifest.get(key)
        if type(value) is not int or value < minimum:
            raise DatasetError(f"{path}: manifest key {key!r} must be an integer ≥ {minimum}, got {value!r}")
    recorded = manifest.get("manifest_sha256")
    if recorded is None:
        raise DatasetError(f"{path}: manifest has no manifest_sha256 (written by an older simrig); regenerate it")
    if recorded != manifest_digest(manifest):
        raise DatasetError(f"{path}: manifest was edited after it was written (its content does not match its "
                           "manifest_sha256); regenerate the dataset")
    # a manifest re-hashed after an edit: what it states is still checked against its own limits and tables
    if manifest["frames"] > MAX_FRAMES:
        raise DatasetError(f"{path}: manifest key 'frames' is {manifest['frames']}, more than a sequence may have "
                           f"({MAX_FRAMES:,})")
    rate = manifest.get("frame_rate_hz")
    if rate is not None and (type(rate) not in (int, float) or not 0 < rate <= MAX_FRAME_RATE_HZ):
        raise DatasetError(f"{path}: manifest key 'frame_rate_hz' must be a number in (0, {MAX_FRAME_RATE_HZ:g}], "
                           f"got {rate!r}")
    poses = files.get("ego_poses", {}).get("rows")
    if poses is not None and poses != manifest["frames"]:
        raise DatasetError(f"{path}: manifest says {manifest['frames']} frames but its ego_poses table holds {poses} "
                           "rows (one per frame)")


def write_json_atomic(path: Path, data: dict) -> None:
    """Write ``data`` as JSON to ``path`` through a temporary file, flushed to disk, then renamed. ``data`` is
    serialised first, so data that is not JSON (NaN, infinity) raises before any file is touched."""
    write_text_atomic(path, json.dumps(data, indent=2, sort_keys=False, allow_nan=False) + "\n")


def written_by_simrig(folder: Path) -> bool:
    """Whether ``folder`` holds a ``manifest.json`` that simrig wrote (a JSON object of our format), whatever its
    state: complete or not, damaged or from an older simrig. Such a folder is one ``--overwrite`` may replace."""
    try:
        manifest = json.loads(read_capped(folder / MANIFEST_NAME, "manifest", DatasetError))
    except (OSError, ValueError, DatasetError):
        return False
    return isinstance(manifest, dict) and manifest.get("format") == FORMAT_NAME


def read_manifest(folder: Path) -> dict | None:
    """The manifest of ``folder`` if it exists and says ``complete: true``; ``None`` otherwise."""
    path = folder / MANIFEST_NAME
    try:
        manifest = read_json(path, "manifest", DatasetError)
    except FileNotFoundError:
        return None
    if not isinstance(manifest, dict) or manifest.get("complete") is not True:
        return None
    if manifest.get("format") != FORMAT_NAME:
        raise DatasetError(f"{path}: not a {FORMAT_NAME} manifest (format {manifest.get('format')!r})")
    if manifest.get("format_version") != FORMAT_VERSION:
        raise DatasetError(
            f"{path}: format_version {manifest.get('format_version')!r}; this simrig reads {FORMAT_VERSION}"
        )
    _check_manifest(path, manifest)
    return manifest
