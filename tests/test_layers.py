"""No module imports from a layer above its own (docs/architecture.md, "Layout and layers"): read every import of
every module.

Imports inside functions count too: a lazy import is still a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = {"simrig": ROOT / "simrig", "simrig.trackers": ROOT / "tracker", "simrig.scenarios": ROOT / "scenarios"}

# Bottom to top. A module belongs to the first layer one of whose prefixes it starts with.
LAYERS: dict[str, tuple[str, ...]] = {
    "records": ("simrig.types", "simrig.errors", "simrig.seeding", "simrig.classes", "simrig.causes",
                "simrig.road", "simrig.version", "simrig.lifeline", "simrig.names", "simrig.reading", "simrig.markdown",
                "simrig.interrupts", "simrig.installation", "simrig.engine_names", "simrig.pools"),
    "scenarios": ("simrig.scenarios",),
    "geometry": ("simrig.geometry", "simrig.rig"),
    "trackers": ("simrig.trackers",),
    "making data": ("simrig.world", "simrig.render", "simrig.sensor"),
    "storage": ("simrig.dataset",),
    "formats": ("simrig.formats",),
    "judging": ("simrig.scoring", "simrig.detector"),
    "pipeline": ("simrig.pipeline",),
    "orchestration": ("simrig.benchmark", "simrig.search", "simrig.testing", "simrig.explain", "simrig.collection"),
    "faces": ("simrig.report", "simrig.figures", "simrig.cli", "simrig.api", "simrig.__main__", "simrig"),
}
BELOW_DATA = ("records", "scenarios", "geometry")
ALLOWED: dict[str, set[str]] = {
    "records": {"records"},
    "scenarios": {"records", "scenarios"},
    "geometry": {"records", "scenarios", "geometry"},  # a rig is built from its validated settings
    "trackers": {"records", "geometry", "trackers"},  # never the world, renderer, sensor, dataset or scorer
    "making data": {*BELOW_DATA, "making data"},
    "storage": {*BELOW_DATA, "storage"},  # tables and records only: what made them is the pipeline's business
    "formats": {*BELOW_DATA, "storage", "formats"},  # outside formats over simrig's own storage
    "judging": {*BELOW_DATA, "making data", "storage", "formats", "judging"},  # never a tracker: each is a black box
    "pipeline": set(LAYERS) - {"orchestration", "faces"},
    "orchestration": set(LAYERS) - {"faces"},
    "faces": set(LAYERS),
}


def layer_of(module: str) -> str | None:
    best = None
    for layer, prefixes in LAYERS.items():
        for prefix in prefixes:
            inside = module == prefix or (module.startswith(prefix + ".") and prefix != "simrig")  # no catch-all
            if inside and (best is None or len(prefix) > best[1]):
                best = (layer, len(prefix))
    return best[0] if best else None


def modules() -> dict[str, Path]:
    """Every module of the installed package by its import name."""
    out = {}
    for package, folder in FOLDERS.items():
        for path in folder.rglob("*.py"):
            parts = path.relative_to(folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join((package, *parts))] = path
    return out


def imported(module: str, path: Path) -> set[str]:
    """The simrig modules that ``module`` imports (absolute and relative, at any depth of the file)."""
    is_package = path.name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.add(target)
            found.update(f"{target}.{alias.name}" for alias in node.names)  # "from . import x" names a module
    known = modules()
    return {name for name in found if name in known}


def test_every_module_has_a_layer() -> None:
    assert [name for name in modules() if layer_of(name) is None] == []


def test_no_module_imports_from_a_layer_above_its_own() -> None:
    found = modules()
    upward = []
    for module, path in sorted(found.items()):
        mine = layer_of(module)
        for target in sorted(imported(module, path)):
            if layer_of(target) not in ALLOWED[mine]:
                upward.append(f"{module} ({mine}) imports {target} ({layer_of(target)})")
    assert upward == []


@pytest.mark.parametrize(("module", "layer"), [
    ("simrig.types", "records"), ("simrig.trackers.saga", "trackers"), ("simrig.scoring.hota", "judging"),
    ("simrig", "faces"), ("simrig.scenarios.schema", "scenarios"), ("simrig.pipeline.run", "pipeline"),
])
def test_layer_of(module: str, layer: str) -> None:
    assert layer_of(module) == layer


def test_the_checker_sees_relative_and_function_level_imports(tmp_path: Path) -> None:
    source = tmp_path / "probe.py"
    source.write_text("def f():\n    from ..scoring import hota\n    from simrig.pipeline import run\n")
    assert imported("simrig.sensor.probe", source) >= {"simrig.scoring", "simrig.scoring.hota", "simrig.pipeline.run"}


def runtime_imported(module: str, path: Path) -> set[str]:
    """The simrig modules importing ``module`` executes: as :func:`imported`, without imports under
    ``if TYPE_CHECKING:`` (never run) and without ``module``'s own packages (running already when it is
    imported); ``from package import submodule`` names the submodule only."""
    is_package = path.name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    guards = [node for node in ast.walk(tree) if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)]
    unrun = {id(inner) for guard in guards for statement in guard.body for inner in ast.walk(statement)}
    known = modules()
    found = set()
    for node in ast.walk(tree):
        if id(node) in unrun:
            continue
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                target = ".".join(base[: len(base) - (node.level - 1)] + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            submodules = {f"{target}.{alias.name}" for alias in node.names} & set(known)
            found |= submodules
            if len(submodules) < len(node.names):
                found.add(target)
    own_packages = {module.rsplit(".", k)[0] for k in range(1, module.count(".") + 1)}
    return {name for name in found if name in known and name != module and name not in own_packages}


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(module: str) -> None:
        index[module] = low[module] = len(index)
        stack.append(module)
        on_stack.add(module)
        for target in sorted(graph.get(module, ())):
            if target not in index:
                visit(target)
                low[module] = min(low[module], low[target])
            elif target in on_stack:
                low[module] = min(low[module], index[target])
        if low[module] == index[module]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == module:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return cycles


def test_no_import_cycle_between_modules_counting_imports_inside_functions() -> None:
    graph = {module: runtime_imported(module, path) for module, path in modules().items()}
    assert import_cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle_through_a_function_level_import(tmp_path: Path) -> None:
    first, second = tmp_path / "first.py", tmp_path / "second.py"
    first.write_text("from simrig.pipeline import generate\n")
    second.write_text("def later():\n    from simrig.pipeline.cache import cached_dataset\n")
    graph = {"simrig.pipeline.cache": runtime_imported("simrig.pipeline.cache", first),
             "simrig.pipeline.generate": runtime_imported("simrig.pipeline.generate", second)}
    assert import_cycles(graph) == [["simrig.pipeline.cache", "simrig.pipeline.generate"]]


def _documented_layers() -> list[tuple[str, str]]:
    """(layer name, its paragraph) of the numbered layer list in docs/architecture.md, bottom first."""
    import re

    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    found = re.findall(r"^\s*\d+\. \*\*([a-z ]+)\*\* — (.*?)(?=^\s*\d+\. \*\*|^\S|\Z)", text, flags=re.M | re.S)
    return [(name, " ".join(paragraph.split())) for name, paragraph in found]


def test_the_layer_map_in_the_docs_is_the_tests() -> None:
    documented = _documented_layers()
    assert [name for name, _ in documented] == list(LAYERS)
    known = modules()
    missing = []
    for (layer, paragraph), prefixes in zip(documented, LAYERS.values(), strict=True):
        for prefix in prefixes:
            if prefix not in known:
                continue  # a name the map reserves for a module not written
            last = prefix.rpartition(".")[2]
            tokens = (f"{last}.py", f"{last}/", prefix, f"`{prefix}`")
            if prefix == "simrig":
                tokens = ("simrig/__init__.py",)
            if not any(token in paragraph for token in tokens):
                missing.append(f"{layer}: {prefix}")
    assert missing == []


def test_every_all_names_only_what_its_module_has() -> None:
    """``__all__`` is true: every name it lists exists in its module (18 modules declare one)."""
    import importlib

    declared, missing = 0, []
    for module, path in sorted(modules().items()):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        if not any(isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in node.targets)
                   for node in tree.body):
            continue
        declared += 1
        loaded = importlib.import_module(module)
        missing += [f"{module}.{name}" for name in loaded.__all__ if not hasattr(loaded, name)]
    assert declared >= 10 and missing == []


def test_every_file_the_architecture_page_walks_through_exists():
    import re

    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    walk = text.split("## One setting, end to end", 1)[1].split("\n## ", 1)[0]
    named = set(re.findall(r"`((?:simrig|scenarios|tracker|tests)/[\w/]+\.py)`", walk))
    assert len(named) >= 10 and [path for path in sorted(named) if not (ROOT / path).is_file()] == []
