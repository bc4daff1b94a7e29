"""Write only where told, delete only what simrig wrote, and notice tampering: ``--overwrite`` never removes a
dataset or a folder of the user's files, outputs inside an input / under a file / in system folders are refused
before any work, a manifest cannot point outside its folder, and an edited table or manifest is refused in one
line naming it."""

import json
import shutil
import subprocess
import sys

import pytest

from simrig.cli import main
from simrig.dataset import Dataset
from simrig.errors import DatasetError
from simrig.pipeline.track import run_tracker


def _tree(folder):
    """Every file under ``folder`` with its bytes: what must survive a refused command unchanged."""
    return {path.relative_to(folder).as_posix(): path.read_bytes() for path in sorted(folder.rglob("*"))
            if path.is_file()}


def _error(capsys):
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("simrig: error: "), err
    return lines[0]


@pytest.fixture
def dataset_copy(small_dataset, tmp_path):
    """A private copy of the small dataset (tests below tamper with it)."""
    return Dataset.open(shutil.copytree(small_dataset.path, tmp_path / "ds"))


@pytest.fixture(scope="module")
def tracks(small_dataset, tmp_path_factory):
    return run_tracker(small_dataset, "saga", tmp_path_factory.mktemp("tracks") / "saga").out


def test_export_overwrite_pointed_at_a_dataset_or_user_files_deletes_nothing(dataset_copy, small_dataset, tmp_path,
                                                                          capsys):
    user = tmp_path / "my_files"
    user.mkdir()
    (user / "thesis.tex").write_text("years of work")
    other = Dataset.open(shutil.copytree(small_dataset.path, tmp_path / "other"))
    before = {folder: _tree(folder) for folder in (dataset_copy.path, other.path, user)}
    cases = {
        dataset_copy.path: "is inside the input",  # the dataset being exported
        tmp_path: "holds the input",  # a parent folder of the dataset (and of the user's files)
        other.path: "was not written by simrig export",  # another dataset
        user: "was not written by simrig export",  # a folder of user files
    }
    for out, message in cases.items():
        code = main(["export", str(dataset_copy.path), "--format", "kitti", "--out", str(out), "--overwrite"])
        assert code == 2 and message in _error(capsys), out
    assert {folder: _tree(folder) for folder in before} == before
    assert not list(tmp_path.glob(".*partial*"))
    # an earlier export is what --overwrite does replace
    out = tmp_path / "export"
    assert main(["export", str(dataset_copy.path), "--format", "kitti", "--out", str(out)]) == 0
    written = sorted(p.relative_to(out) for p in out.rglob("*") if p.is_file())
    original = {path: (out / path).read_bytes() for path in written}
    (out / written[0]).write_text("edited")  # simrig's file: replaced
    (out / "notes.txt").write_text("mine")  # the user's: kept (only what the marker lists is deleted)
    assert main(["export", str(dataset_copy.path), "--format", "kitti", "--out", str(out), "--overwrite"]) == 0
    assert {path: (out / path).read_bytes() for path in written} == original
    assert (out / "notes.txt").read_text() == "mine"


def test_generate_overwrite_replaces_only_a_dataset(small_scenario, tmp_path, capsys):
    user = tmp_path / "notes"
    user.mkdir()
    (user / "a.txt").write_text("mine")
    assert main(["generate", "--out", str(user), "--overwrite", "--frames", "2", "--quiet"]) == 2
    assert "holds no simrig dataset" in _error(capsys)
    assert (user / "a.txt").read_text() == "mine"


def test_outputs_inside_an_input_under_a_file_or_in_system_folders_are_refused_before_any_work(
        dataset_copy, tracks, tmp_path, capsys):
    before = _tree(dataset_copy.path)
    a_file = tmp_path / "plain.txt"
    a_file.write_text("x")
    ds, tr = str(dataset_copy.path), str(tracks)
    cases = [
        (["score", ds, tr, "--json", f"{ds}/manifest.json"], "is inside the input"),
        (["score", ds, tr, "--errors", f"{ds}/ground_truth.parquet"], "is inside the input"),
        (["score", ds, tr, "--json", f"{tr}/tracks3d.parquet"], "is inside the input"),
        (["score", ds, tr, "--json", f"{a_file}/score.json"], "which is a file"),
        (["score", ds, tr, "--json", "/proc/score.json"], "system folder /proc"),
        (["track", ds, "--out", f"{ds}/tracks"], "is inside the input"),
        (["track", ds, "--out", str(tmp_path)], "holds the input"),
        (["track", ds, "--out", f"{a_file}/t"], "which is a file"),
        (["generate", "--out", "/proc/ds", "--frames", "2"], "system folder /proc"),
        (["generate", "--out", f"{a_file}/ds", "--frames", "2"], "which is a file"),
        (["generate", "--out", str(a_file), "--frames", "2"], "is a file, not a folder"),
        (["run", "--out", "/etc/simrig", "--frames", "2"], "system folder /etc"),
        (["export", ds, "--format", "motchallenge", "--out", "/sys/x"], "system folder /sys"),
        (["render", ds, "--frame", "0", "--out", f"{ds}/detections.parquet"], "name a .png file"),
        (["bench", "smoke", "--out", str(tmp_path)], "holds no bench.json"),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        assert message in _error(capsys), argv
    assert _tree(dataset_copy.path) == before
    assert a_file.read_text() == "x"
    # a missing folder for --json is created, not a traceback
    assert main(["score", ds, tr, "--json", str(tmp_path / "new" / "deep" / "score.json")]) == 0
    assert json.loads((tmp_path / "new" / "deep" / "score.json").read_text())["seed"] == 0


def test_replay_out_does_not_delete_a_folder_simrig_did_not_write(small_scenario, tmp_path, capsys):
    from simrig.testing import write_replay

    replay_file = write_replay(tmp_path / "r.toml", small_scenario.model_copy(update={"frames": 3}), 0,
                               tracker="saga")
    replay_file.write_text(replay_file.read_text().replace("[scores]", "[scores.2d]\nHOTA = 0.5"))
    (tmp_path / "out" / "dataset").mkdir(parents=True)
    (tmp_path / "out" / "dataset" / "photo.jpg").write_bytes(b"\xff\xd8")
    assert main(["replay", str(replay_file), "--out", str(tmp_path / "out")]) == 2
    assert "holds no simrig dataset" in _error(capsys)
    assert (tmp_path / "out" / "dataset" / "photo.jpg").read_bytes() == b"\xff\xd8"


def _edit_manifest(folder, change):
    path = folder / "manifest.json"
    manifest = json.loads(path.read_text())
    change(manifest)
    path.write_text(json.dumps(manifest, indent=2))


def test_a_manifest_cannot_point_outside_its_folder(dataset_copy, capsys):
    def outside(manifest):
        manifest["files"]["rig"]["file"] = "../../etc/hostname"

    _edit_manifest(dataset_copy.path, outside)
    with pytest.raises(DatasetError, match=r"files\.rig\.file must be a plain file name"):
        Dataset.open(dataset_copy.path)
    assert main(["info", str(dataset_copy.path)]) == 2
    assert "files.rig.file" in _error(capsys)


def test_score_on_a_dataset_with_one_edited_table_is_refused_naming_the_table(dataset_copy, tracks, tmp_path,
                                                                              capsys):
    import pyarrow.parquet as pq

    assert main(["score", str(dataset_copy.path), str(tracks)]) == 0
    capsys.readouterr()
    truth = pq.read_table(dataset_copy.path / "ground_truth.parquet")
    pq.write_table(truth.slice(0, truth.num_rows - 1), dataset_copy.path / "ground_truth.parquet")
    code = main(["score", str(dataset_copy.path), str(tracks), "--json", str(tmp_path / "s.json")])
    line = _error(capsys)
    assert code == 2 and "ground_truth (ground_truth.parquet) does not match its SHA-256" in line
    assert not (tmp_path / "s.json").exists()
    (dataset_copy.path / "detections.parquet").unlink()
    assert main(["track", str(dataset_copy.path), "--out", str(tmp_path / "t")]) == 2
    assert "detections (detections.parquet) is missing" in _error(capsys)


def test_info_verify_covers_the_manifest_and_reports_extra_files(dataset_copy, capsys):
    (dataset_copy.path / "notes.txt").write_text("added by hand")
    assert main(["info", str(dataset_copy.path), "--verify"]) == 0
    assert "extra     1 file(s) not in the manifest (not part of the dataset): notes.txt" in capsys.readouterr().out

    def more_frames(manifest):
        manifest["frames"] = manifest["frames"] + 1

    _edit_manifest(dataset_copy.path, more_frames)
    assert main(["info", str(dataset_copy.path), "--verify"]) == 2
    assert "manifest was edited after it was written" in _error(capsys)


def test_partial_folders_are_unique_per_process(tmp_path):
    code = "import sys; from pathlib import Path; from simrig.dataset.outputs import partial_sibling; " \
           "print(partial_sibling(Path(sys.argv[1])).name)"
    names = {subprocess.run([sys.executable, "-c", code, str(tmp_path / "out")], capture_output=True, text=True,
                            check=True).stdout.strip() for _ in range(2)}
    assert len(names) == 2 and all(name.startswith(".out.partial-") for name in names)


def test_a_damaged_or_older_simrig_dataset_is_replaced_only_with_overwrite(small_scenario, tmp_path, capsys):
    """A dataset whose manifest no longer checks out (edited, or written before manifest_sha256) is still simrig's:
    refused without --overwrite, regenerated with it (the bench's cache does so on its own)."""
    from simrig.pipeline.cache import cached_dataset

    scenario = small_scenario.model_copy(update={"frames": 3})
    first = cached_dataset(scenario, 0, None, tmp_path / "cache")
    _edit_manifest(first.path, lambda manifest: manifest.pop("manifest_sha256"))
    again = cached_dataset(scenario, 0, None, tmp_path / "cache")  # regenerated in place
    assert again.path == first.path and "manifest_sha256" in again.manifest
    _edit_manifest(again.path, lambda manifest: manifest.update(frames=99))
    argv = ["generate", "--frames", "2", "--out", str(again.path), "--quiet"]
    assert main(argv) == 2 and "holds a simrig dataset that cannot be read" in _error(capsys)
    assert main([*argv, "--overwrite"]) == 0
    assert Dataset.open(again.path).frame_count == 2


def test_a_json_document_that_cannot_be_written_leaves_no_file_behind(tmp_path):
    # New-user trial: an explain.json with an infinite value left explain.json.tmp beside the run's files.
    from simrig.dataset.manifest import write_json_atomic

    (tmp_path / "keep.json").write_text('{"old": true}\n')
    with pytest.raises(ValueError, match="not JSON compliant"):
        write_json_atomic(tmp_path / "keep.json", {"share": float("inf")})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.json"]
    assert (tmp_path / "keep.json").read_text() == '{"old": true}\n'
