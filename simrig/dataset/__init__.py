"""The on-disk dataset: one folder per (scenario, seed), written atomically, read back into records.

Layout: ``manifest.json`` (resolved scenario, seed, package versions, row counts, SHA-256 per file,
``complete: true`` last), ``ego_poses.parquet``, ``ground_truth.parquet``, ``projections.parquet``
(:mod:`.tables` documents their columns and units) and ``rig.json``.
"""

from .manifest import MANIFEST_NAME, read_manifest
from .reader import Dataset
from .writer import DatasetWriter, check_output_folder

__all__ = ["MANIFEST_NAME", "Dataset", "DatasetWriter", "check_output_folder", "read_manifest"]
