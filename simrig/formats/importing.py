"""``simrig import``: ground truth made elsewhere as a simrig dataset that ``score``, ``render`` and ``view`` read.

Formats: ``motchallenge`` (:mod:`simrig.formats.motchallenge.ground_truth`: 2D boxes, one camera per
sequence), ``kitti`` (:mod:`simrig.formats.kitti.ground_truth`: KITTI tracking labels, 2D boxes, one camera per
sequence) and ``nuscenes`` (:mod:`simrig.formats.nuscenes.ground_truth`: the nuScenes tables, world-frame 3D
boxes with ego poses, no cameras). :mod:`simrig.formats.imported_truth` says what an imported dataset holds and
how what the source lacks is marked unknown.
"""

from __future__ import annotations

from pathlib import Path

from simrig.dataset.outputs import check_output_path
from simrig.formats import OUTSIDE_FORMATS
from simrig.formats.imported_truth import SourceError

FORMATS = OUTSIDE_FORMATS


def import_dataset(fmt: str, src: Path | str, out: Path | str, *, overwrite: bool = False) -> dict:
    """Import the ground truth at ``src`` (format ``fmt``) as the dataset folder ``out``; returns its manifest.
    ``out`` must not hold a dataset (unless ``overwrite``) or anything else, nor lie inside ``src``."""
    from simrig.formats.imported_truth import write_imported

    if fmt not in FORMATS:
        raise SourceError(f"--format {fmt!r}: import formats are {', '.join(FORMATS)}")
    src = Path(src)
    if not src.exists():
        raise SourceError(f"{str(src)!r} does not exist")
    out = check_output_path(out, what="--out", inputs=(src,))
    if fmt == "motchallenge":
        from simrig.formats.motchallenge.ground_truth import read_motchallenge_truth as read
    elif fmt == "kitti":
        from simrig.formats.kitti.ground_truth import read_kitti_truth as read
    else:
        from simrig.formats.nuscenes.ground_truth import read_nuscenes_truth as read
    from simrig.dataset.writer import check_output_folder

    check_output_folder(out, overwrite=overwrite)  # before reading a large source
    return write_imported(read(src), out, overwrite=overwrite)


__all__ = ["FORMATS", "SourceError", "import_dataset"]
