"""A dataset folder's files as its manifest lists them: each read or opened only after its SHA-256 matches the
manifest's (a table edited after it was written is refused, naming the table), and the folder checked whole by
:meth:`ManifestFiles.verify` (``simrig info --verify``)."""

from __future__ import annotations

import hashlib
from functools import cached_property
from pathlib import Path

from ..errors import DatasetError
from ..reading import read_capped
from .manifest import MANIFEST_NAME, file_sha256, folder_digest


class ManifestFiles:
    """The files of the dataset folder ``path`` listed by its ``manifest``."""

    def __init__(self, path: Path, manifest: dict):
        self.path = path
        self.manifest = manifest

    def verify(self) -> list[str]:
        """Check every listed file (and the image folder's digest) against the manifest; the files in the folder
        that the manifest does not list, sorted, relative to the folder."""
        for name in self.manifest["files"]:
            self._check_file(name)
        images = self.manifest.get("images")
        if images is not None and folder_digest(self.path / images["folder"]) != images:
            raise DatasetError(f"{self.path}: the images under {images['folder']!r} do not match the manifest")
        listed = {entry["file"] for entry in self.manifest["files"].values()} | {MANIFEST_NAME}
        image_folder = self.path / images["folder"] if images is not None else None
        extra = []
        for path in self.path.rglob("*"):
            if path.is_dir() or (image_folder is not None and image_folder in path.parents):
                continue
            if path.parent == self.path and path.name in listed:
                continue
            extra.append(path.relative_to(self.path).as_posix())
        return sorted(extra)

    def _entry_file(self, name: str) -> Path:
        """The file of manifest entry ``name``; a one-line :class:`DatasetError` when the manifest lists none."""
        entry = self.manifest["files"].get(name)
        if entry is None:
            raise DatasetError(f"dataset {str(self.path)!r}: the manifest lists no {name!r}")
        return self.path / entry["file"]

    def _check_sha256(self, name: str, digest: str) -> None:
        entry = self.manifest["files"][name]
        if digest != entry["sha256"]:
            raise DatasetError(f"dataset {str(self.path)!r}: {name} ({entry['file']}) does not match its SHA-256 "
                               "in the manifest (changed after it was written); regenerate the dataset")

    def _unreadable(self, name: str, error: OSError) -> DatasetError:
        entry = self.manifest["files"][name]
        if isinstance(error, FileNotFoundError):
            return DatasetError(f"dataset {str(self.path)!r}: {name} ({entry['file']}) is missing")
        return DatasetError(f"dataset {str(self.path)!r}: cannot read {name} ({entry['file']}): "
                            f"{error.strerror or error}")

    def read(self, name: str) -> bytes:
        """The bytes of manifest entry ``name`` (a small side file), checked against its SHA-256; a one-line
        :class:`DatasetError` naming the dataset and the table when it is missing or changed."""
        file = self._entry_file(name)
        try:
            data = read_capped(file, f"{self.path}: {name}", DatasetError)
        except OSError as error:
            raise self._unreadable(name, error) from None
        self._check_sha256(name, hashlib.sha256(data).hexdigest())
        return data

    def verified(self, name: str) -> Path:
        """The file of manifest entry ``name`` once its SHA-256 (hashed in blocks, never held in memory whole)
        matches the manifest; checked once per object. Errors as :meth:`read`'s."""
        if name not in self._verified:
            self._check_file(name)
            self._verified.add(name)
        return self._entry_file(name)

    def _check_file(self, name: str) -> None:
        """Hash the file of manifest entry ``name`` in blocks and compare with the manifest."""
        try:
            digest = file_sha256(self._entry_file(name))
        except OSError as error:
            raise self._unreadable(name, error) from None
        self._check_sha256(name, digest)

    @cached_property
    def _verified(self) -> set[str]:
        """Manifest entries whose file matched its SHA-256."""
        return set()
