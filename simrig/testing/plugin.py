"""simrig's pytest plugin (entry point ``pytest11: simrig``), loaded by any pytest where simrig is installed.

Fixtures:

* ``simrig_scenario`` — a factory: ``simrig_scenario("highway_stereo", frames=10, traffic={"vehicles": 5})``
  returns a validated scenario from a catalog name or file with tables merged key by key;
* ``simrig_dataset`` — a small generated dataset (``highway_surround6``, 12 frames, 8 vehicles, seed 0), once
  per session.

Replayable failures: when a test that ran :func:`simrig.testing.run_tracker` fails, the last scenario it ran —
the shrunk one, under hypothesis — is written to ``simrig-failures/TEST.toml`` under the rootdir (or
``--simrig-failures DIR``), and the failure report gets a section with the path and the ``simrig replay``
command. Nothing here imports hypothesis, the renderer or highway-env until a fixture or a run needs them.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest


def pytest_report_header(config):
    """A line in pytest's header when another distribution owns files of the simrig package
    (:mod:`simrig.installation`)."""
    from simrig.installation import ownership_warning

    warning = ownership_warning()
    return [warning] if warning else []


def pytest_addoption(parser):
    parser.addoption("--simrig-failures", default=None, metavar="DIR",
                     help="where simrig writes replay files of failing tests (default: ROOTDIR/simrig-failures)")


@pytest.fixture
def simrig_scenario():
    """Build a scenario from a catalog name or file, overriding any key (tables merge key by key)."""
    from simrig.scenarios import load_scenario
    from simrig.scenarios.schema import Scenario

    def build(base: str = "highway_surround6", **overrides) -> Scenario:
        raw = load_scenario(base).model_dump(mode="json", exclude_none=True, exclude_unset=True)
        for key, value in overrides.items():
            raw[key] = {**raw.get(key, {}), **value} if isinstance(value, dict) else value
        return Scenario.model_validate(raw)

    return build


@pytest.fixture(scope="session")
def simrig_dataset():
    """A small generated dataset: ``highway_surround6``, 12 frames, 8 vehicles, seed 0."""
    from simrig.scenarios import load_scenario
    from simrig.scenarios.schema import Scenario

    from .runs import dataset_for

    raw = load_scenario("highway_surround6").model_dump(mode="json", exclude_none=True, exclude_unset=True)
    raw.update(frames=12, name="simrig_dataset")
    raw["traffic"] = {**raw.get("traffic", {}), "vehicles": 8, "window_radius_m": 100.0, "spawn_min_distance_m": 70.0}
    return dataset_for(Scenario.model_validate(raw), seed=0)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    from . import runs

    runs.clear_runs()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.when != "call" or not report.failed:
        return
    from . import runs

    recorded = runs.recorded_runs()
    if not recorded:
        return
    from .replay import write_replay

    last = recorded[-1]
    folder = item.config.getoption("--simrig-failures") or Path(item.config.rootpath) / "simrig-failures"
    path = Path(folder) / (re.sub(r"[^\w.-]+", "_", item.nodeid.split("::", 1)[-1]) + ".toml")
    message = str(call.excinfo.value) if call.excinfo is not None else ""
    written = write_replay(path, last.scenario, last.seed, tracker=last.tracker, params=last.params,
                           failure=message, scores=last.scores)
    # a module:attribute tracker is named on the command line: the file alone may not import it
    from simrig.pipeline.trust import is_import_reference

    imported = is_import_reference(last.tracker)
    command = shlex.join(["simrig", "replay", str(written)]
                         + (["--tracker", last.tracker] if imported else [])
                         + ([] if last.tracker else ["--tracker", "NAME"]))
    root = _import_root(last.tracker) if imported else None
    if root is not None:  # the module was found on a path pytest added: the simrig command needs it too
        command = f"PYTHONPATH={shlex.quote(str(root))} {command}"
    report.sections.append(("simrig replay", f"scenario of the failing run written to {written}\n"
                                             f"reproduce it with: {command}"))


def _import_root(spec: str) -> Path | None:
    """The folder on ``sys.path`` that a ``module:attribute`` tracker's module was imported from, when that is
    not where installed packages live (a project folder pytest or ``PYTHONPATH`` put on the path); ``None``
    otherwise. Works for a plain module, a package and a namespace package (a folder without ``__init__.py``)."""
    import sys
    import sysconfig

    name = spec.partition(":")[0]
    origin = getattr(getattr(sys.modules.get(name), "__spec__", None), "origin", None)
    if not origin or not Path(origin).is_file():
        return None
    path = Path(origin).resolve()
    root = path.parent  # the module's folder, then one level up per dot (and one more for a package)
    for _ in range(name.count(".") + (path.name == "__init__.py")):
        root = root.parent
    installed = {Path(sysconfig.get_paths()[key]).resolve() for key in ("purelib", "platlib", "stdlib")}
    on_path = {Path(entry or ".").resolve() for entry in sys.path}  # found through a path entry, not a finder hook
    return root if root in on_path and root not in installed else None
