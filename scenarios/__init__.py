"""The scenario catalog and loader.

A scenario is a TOML file validated by :class:`simrig.scenarios.schema.Scenario`. Catalog entries live next to
this module (``scenarios/<name>.toml``). A user's file may start from a catalog entry with
``extends = "name"`` and override only what it changes; tables are merged key by key, other values are
replaced. One exception: a ``[traffic] layout`` of the file's own replaces the parent's road — the parent's
``lanes`` and ``ego_lane``, and its layout when that is of another kind.

>>> load_scenario("highway_surround6").rig.preset
'surround6'
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pydantic import ValidationError

    from .schema import Scenario

from .files import read_toml, validate_strict
from .merge import merge

CATALOG_DIR = Path(__file__).resolve().parent
SUITES_DIR = CATALOG_DIR / "suites"
SPACES_DIR = CATALOG_DIR / "spaces"
"""The catalog of search spaces: ``scenarios/spaces/<name>.toml``."""
MAX_FRAMES = 1_000_000
"""The most frames one sequence may have (``--frames``, a dataset's manifest)."""
MAX_SEQUENCES = 1_000_000
"""The most sequences ``simrig generate --space`` samples into one collection (six-digit sequence folders)."""
DEFAULT_SCENARIO = "highway_surround6"
_NAMED_MESSAGE = re.compile(r"^([a-z_][a-z0-9_]*(?:\.[A-Za-z0-9_]+)*(?:, [a-z_][a-z0-9_]*)*): (.*)$")

__all__ = ["CATALOG_DIR", "DEFAULT_SCENARIO", "MAX_FRAMES", "MAX_SEQUENCES", "SPACES_DIR", "SUITES_DIR", "Scenario",
           "ScenarioError", "catalog", "dimension_labels", "describe_errors", "load_scenario", "space_catalog",
           "suite_catalog"]


class ScenarioError(ValueError):
    """A scenario cannot be found or is invalid; the message names the file and the key."""


def __getattr__(name: str):
    """``Scenario`` on first use: the schema (pydantic) loads only when a scenario is validated, so that listing
    the catalog or building the command line stays cheap."""
    if name == "Scenario":
        from .schema import Scenario

        return Scenario
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def catalog() -> dict[str, Path]:
    """Catalog entries by name, sorted by name."""
    return {path.stem: path for path in sorted(CATALOG_DIR.glob("*.toml"))}


def space_catalog() -> dict[str, Path]:
    """Named search spaces (``simrig search NAME``) by name, sorted by name."""
    return {path.stem: path for path in sorted(SPACES_DIR.glob("*.toml"))}


def suite_catalog() -> dict[str, Path]:
    """Named bench suites (``simrig bench NAME``) by name, sorted by name."""
    return {path.stem: path for path in sorted(SUITES_DIR.glob("*.toml"))}


def _read_toml(path: Path) -> dict[str, Any]:
    return read_toml(path, "scenario file", ScenarioError)


def _resolve(path: Path, chain: tuple[Path, ...]) -> dict[str, Any]:
    """The raw dict of ``path`` with its ``extends`` chain merged in (parents first)."""
    if path in chain:
        cycle = " -> ".join(p.name for p in (*chain, path))
        raise ScenarioError(f"scenario file {str(path)!r}: 'extends' forms a cycle: {cycle}")
    raw = _read_toml(path)
    parent = raw.pop("extends", None)
    if parent is None:
        return raw
    if not isinstance(parent, str):
        raise ScenarioError(f"scenario file {str(path)!r}: extends: must be a catalog name (a string)")
    entries = catalog()
    if parent not in entries:
        raise ScenarioError(
            f"scenario file {str(path)!r}: extends: unknown catalog scenario {parent!r}; "
            f"known: {', '.join(entries)}"
        )
    base = _resolve(entries[parent], (*chain, path))
    base.pop("name", None)  # a derived scenario is named by its own file
    return merge(_road_replaced(base, raw), raw)


def _road_replaced(base: dict[str, Any], raw: dict[str, Any]) -> dict[str, Any]:
    """``base`` without what describes its road when ``raw`` brings a road layout of its own: a layout replaces
    the parent's road, so the parent's ``lanes`` and ``ego_lane`` (highway-v0's) are dropped, and a parent's layout
    of another kind is replaced whole rather than merged key by key (its keys belong to that kind)."""
    layout = raw.get("traffic", {}).get("layout") if isinstance(raw.get("traffic"), dict) else None
    traffic = base.get("traffic")
    if not isinstance(layout, dict) or not isinstance(traffic, dict):
        return base
    traffic = {key: value for key, value in traffic.items() if key not in ("lanes", "ego_lane")}
    inherited = traffic.get("layout")
    if isinstance(inherited, dict) and inherited.get("kind") != layout.get("kind", inherited.get("kind")):
        traffic.pop("layout")
    return {**base, "traffic": traffic}


MAX_ERRORS_LISTED = 10
"""Validation errors named in one message; the rest are counted."""


def describe_errors(error: ValidationError, labels: dict[tuple, str] | None = None) -> str:
    """One line per pydantic error folded into one line: 'key.path: message' (the first
    :data:`MAX_ERRORS_LISTED`, then how many more). ``labels`` name a key's leading parts in full (a space's
    ``("dimensions", 0)`` as ``dimensions.0 (traffic.vehicles)``: :func:`dimension_labels`)."""
    from .key_hints import known_keys, nearest  # only on an error: pydantic's models are not loaded for --help

    parts = []
    items = error.errors()
    for item in items[:MAX_ERRORS_LISTED]:
        loc = tuple(item["loc"])
        label = (labels or {}).get(loc[:2])
        names = [label, *map(str, loc[2:])] if label else [str(part) for part in loc]
        key = ".".join(names) or "(top level)"
        message = item["msg"]
        if item["type"] == "extra_forbidden":
            message = "unknown key" + nearest(str(loc[-1]), known_keys(error.title, loc[:-1])) if loc else "unknown key"
        elif item["type"] == "union_tag_invalid":  # a tagged table whose tag ('kind') names no known kind
            context = item["ctx"]
            tag, field = str(context["tag"]), str(context["discriminator"]).strip("'")
            expected = [name.strip().strip("'") for name in str(context["expected_tags"]).split(",")]
            key = f"{key}.{field}" if key != "(top level)" else field
            message = f"unknown {field} {tag!r}{nearest(tag, expected)}; known: {context['expected_tags']}"
        elif message.startswith("Value error, "):
            message = message.removeprefix("Value error, ")
            named = _NAMED_MESSAGE.match(message)
            if named:  # a model-level check names its own key: "lanes: only highway-v0 ..."
                prefix = "" if key == "(top level)" else key + "."
                key, message = prefix + named.group(1), named.group(2)
        parts.append(f"{key}: {message}")
    if len(items) > MAX_ERRORS_LISTED:
        parts.append(f"and {len(items) - MAX_ERRORS_LISTED:,} more")
    return "; ".join(parts)


def dimension_labels(raw: dict) -> dict[tuple, str]:
    """Each dimension of a raw space file named by its index and its path (for :func:`describe_errors`)."""
    dimensions = raw.get("dimensions")
    if not isinstance(dimensions, list):
        return {}
    return {("dimensions", index): f"dimensions.{index} ({dimension['path']})"
            for index, dimension in enumerate(dimensions)
            if isinstance(dimension, dict) and isinstance(dimension.get("path"), str) and len(dimension["path"]) < 80}


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A validated :class:`Scenario` from a catalog name or a TOML file path.

    Raises :class:`ScenarioError` with a one-line message naming the file and the offending key.
    """
    entries = catalog()
    text = str(name_or_path)
    if text in entries and not Path(text).suffix:
        path = entries[text]
    else:
        path = Path(text)
        if path.suffix != ".toml" and not path.exists():
            raise ScenarioError(
                f"unknown scenario {text!r}: not a catalog name ({', '.join(entries)}) nor a .toml file"
            )
    from pydantic import ValidationError

    from .schema import Scenario
    from .sensor_presets import with_preset

    raw = _resolve(path, ())
    raw.setdefault("name", path.stem)
    try:
        return validate_strict(Scenario, with_preset(raw))
    except ValidationError as error:
        raise ScenarioError(f"scenario file {str(path)!r}: {describe_errors(error)}") from None
    except ValueError as error:
        raise ScenarioError(f"scenario file {str(path)!r}: {error}") from None
