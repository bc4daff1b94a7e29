"""Shared fixtures: a small scenario that generates in about a second; and the suite on every core."""

import pytest
from simrig.scenarios import load_scenario


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config):
    """Run the tests on every core, one test file per worker, when pytest-xdist is installed (the ``dev`` extra)
    and no ``-n`` was given: ``-n 0`` runs them in this process, as ``--pdb`` does. Here rather than in
    ``addopts``, so that pytest without xdist (a checkout installed without ``dev``) still runs the suite."""
    if hasattr(config, "workerinput") or not config.pluginmanager.hasplugin("xdist"):
        return
    if config.option.numprocesses is None and not config.option.collectonly:
        config.option.numprocesses = "auto"
        if config.option.dist == "no":
            config.option.dist = "loadfile"


@pytest.fixture(autouse=True)
def _tracker_registry_as_the_suite_found_it():
    """Each test sees the tracker registry as it was before the test: a tracker one test registers does not leak
    into the next (with the suite spread over workers, which tests share a process changes from run to run)."""
    from simrig.trackers import registry

    tables = (registry._FACTORIES, registry._LAZY, registry._REGISTERED_HERE)
    saved = [dict(table) for table in tables]
    yield
    for table, before in zip(tables, saved, strict=True):
        table.clear()
        table.update(before)


@pytest.fixture(scope="session")
def release_build(tmp_path_factory):
    """This checkout built once as a release is (``python -m build``: the sdist, then the wheel from the sdist),
    shared by every test and worker of the session: ``(wheel, sdist)``. Built under a lock, because setuptools
    writes into the source tree (its ``*.egg-info``) and two builds of one tree at once break each other."""
    import fcntl
    import os
    import subprocess
    import sys
    from pathlib import Path

    pytest.importorskip("build")
    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # the session's folder, above each worker's own
    out = shared / "release-build"
    repository = Path(__file__).resolve().parents[1]
    with open(shared / "release-build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (out / "done").exists():
            subprocess.run([sys.executable, "-m", "build", "--outdir", str(out), str(repository)], check=True,
                           capture_output=True, timeout=900)
            (out / "done").write_text("")
    (wheel,) = out.glob("simrig_mot-*.whl")
    (sdist,) = out.glob("simrig_mot-*.tar.gz")
    return wheel, sdist


@pytest.fixture
def venv_with_release(tmp_path, release_build) -> str:
    """The Python of a new virtual environment under ``tmp_path`` holding nothing but ``pip install
    simrig-mot[testing] pytest`` from :func:`release_build`'s wheel (pip's message shown if it fails)."""
    import subprocess
    import sys

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = str(venv / "bin" / "python")
    install = subprocess.run([python, "-m", "pip", "install", "-q", f"{release_build[0]}[testing]", "pytest"],
                             timeout=1500, capture_output=True, text=True)
    assert install.returncode == 0, install.stderr[-3000:]
    return python


@pytest.fixture(scope="session")
def small_scenario(tmp_path_factory):
    """highway_surround6 with 15 vehicles in a 100 m window: the default rig, quick to run."""
    path = tmp_path_factory.mktemp("scenario") / "small.toml"
    path.write_text(
        'extends = "highway_surround6"\nframes = 30\n'
        "[traffic]\nvehicles = 15\nwindow_radius_m = 100.0\nspawn_min_distance_m = 70.0\n"
    )
    return load_scenario(path)


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory, small_scenario):
    """A generated 30-frame dataset of ``small_scenario`` (seed 0)."""
    from simrig.dataset import Dataset
    from simrig.pipeline.generate import generate

    out = tmp_path_factory.mktemp("datasets") / "small-seed0"
    generate(small_scenario, seed=0, out=out, progress=False)
    return Dataset.open(out)


@pytest.fixture(scope="session")
def sort_tracks(small_dataset, tmp_path_factory):
    """SORT's tracks (2D, per camera) on ``small_dataset``."""
    from simrig.pipeline.track import run_tracker

    return run_tracker(small_dataset, "sort", tmp_path_factory.mktemp("sort") / "sort").out


@pytest.fixture(scope="session")
def saga_tracks(small_dataset, tmp_path_factory):
    """SAGA's tracks (3D and 2D) on ``small_dataset``."""
    from simrig.pipeline.track import run_tracker

    return run_tracker(small_dataset, "saga", tmp_path_factory.mktemp("saga") / "saga").out


PINNED = ("numpy", "scipy", "pandas", "pyarrow", "highway-env", "gymnasium", "shapely", "filterpy", "pyrender",
          "trackeval", "motmetrics")
"""Packages whose version moves documented numbers: the header says when one differs from constraints.txt."""


def constraint_versions(path) -> dict[str, str]:
    """``name → version`` of every ``name==version`` line of a constraints file (names lower-cased, ``_`` as ``-``)."""
    pins = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        name, equals, version = line.split("#")[0].strip().partition("==")
        if equals:
            pins[name.strip().lower().replace("_", "-")] = version.strip()
    return pins


def pytest_report_header(config):
    """One line when the packages under test are not the versions simrig was last tested with."""
    from importlib import metadata
    from pathlib import Path

    pins = constraint_versions(Path(__file__).resolve().parents[1] / "constraints.txt")
    differ = []
    for name in PINNED:
        try:
            installed = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
        if name in pins and pins[name] != installed:
            differ.append(f"{name} {installed} (tested {pins[name]})")
    if not differ:
        return []
    return ["simrig: not the versions in constraints.txt, so documented numbers may move: " + ", ".join(differ)]
