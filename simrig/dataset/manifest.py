"""The dataset manifest: what a folder holds, how it was made, and whether it is complete.

``manifest.json`` is the last file written into a dataset folder, and its ``complete`` flag is its last
key. A folder without a manifest whose ``complete`` is ``true`` is never read as a dataset.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
from importlib import metadata
from pathlib import Path

from ..errors import DatasetError

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
    with path.open("rb") as handle:
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
    versions = {"python": platform.python_version()}
    for name in _VERSIONED_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def write_json_atomic(path: Path, data: dict) -> None:
    """Write ``data`` as JSON to ``path`` through a temporary file, flushed to disk, then renamed."""
    temporary = path.with_name(path.name + ".tmp")
    with temporary.open("w", encoding="utf-8") as handle:
        json.dump(data, handle, indent=2, sort_keys=False, allow_nan=False)
        handle.write("\n")
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(temporary, path)


def read_manifest(folder: Path) -> dict | None:
    """The manifest of ``folder`` if it exists and says ``complete: true``; ``None`` otherwise."""
    path = folder / MANIFEST_NAME
    try:
        with path.open(encoding="utf-8") as handle:
            manifest = json.load(handle)
    except FileNotFoundError:
        return None
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise DatasetError(f"{path}: manifest is not valid JSON ({error})") from None
    if not isinstance(manifest, dict) or manifest.get("complete") is not True:
        return None
    if manifest.get("format") != FORMAT_NAME:
        raise DatasetError(f"{path}: not a {FORMAT_NAME} manifest (format {manifest.get('format')!r})")
    if manifest.get("format_version") != FORMAT_VERSION:
        raise DatasetError(
            f"{path}: format_version {manifest.get('format_version')!r}; this simrig reads {FORMAT_VERSION}"
        )
    return manifest
