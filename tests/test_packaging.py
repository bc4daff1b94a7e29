"""The installed layout: import names are ``simrig`` and ``simrig.*`` only, and every package folder ships."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {"simrig": "simrig", "simrig.trackers": "tracker", "simrig.scenarios": "scenarios"}


def _config() -> dict:
    with (ROOT / "pyproject.toml").open("rb") as handle:
        return tomllib.load(handle)["tool"]["setuptools"]


def test_package_dirs_map_the_repository_folders_into_the_simrig_namespace() -> None:
    assert _config()["package-dir"] == SOURCES


def _folder(package: str) -> Path:
    """The repository folder of an installed package name, through pyproject's ``package-dir``."""
    for name, folder in sorted(SOURCES.items(), key=lambda item: -len(item[0])):
        if package == name or package.startswith(name + "."):
            return ROOT / folder / Path(*package[len(name):].lstrip(".").split(".") if package != name else ())
    raise AssertionError(f"{package} is under no package-dir entry")


def test_every_package_folder_is_listed_and_nothing_installs_outside_simrig() -> None:
    on_disk = set()
    for name, folder in SOURCES.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            relative = init.parent.relative_to(ROOT / folder).parts
            on_disk.add(".".join((name, *relative)))
    data_only = {name for name in _config()["package-data"] if not any(True for _ in _folder(name).glob("*.py"))}
    listed = set(_config()["packages"])
    assert listed - data_only == on_disk  # a catalog folder of TOML files is listed so that setuptools ships it
    assert all(_folder(name).is_dir() for name in data_only)
    assert all(name == "simrig" or name.startswith("simrig.") for name in listed)
