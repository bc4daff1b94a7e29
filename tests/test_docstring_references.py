"""Every Sphinx-style cross-reference in a docstring (``:func:`~simrig.x.y```, ``:mod:`.shapley```, ...) names
something that exists: a renamed or moved module must take its references with it."""

from __future__ import annotations

import ast
import builtins
import importlib
import re

import pytest
from test_layers import modules

REFERENCE = re.compile(r":(mod|func|class|data|meth|attr|exc|obj):`~?([\w.]+)`")


def _exists(dotted: str) -> bool:
    """Whether ``dotted`` names a module, or an attribute (a dataclass field included) reached from one."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            target = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for position, attribute in enumerate(parts[cut:], start=cut):
            if hasattr(target, attribute):
                target = getattr(target, attribute)
            elif position == len(parts) - 1 and attribute in getattr(target, "__dataclass_fields__", {}):
                return True
            else:
                return False
        return True
    return False


def _bare_name_exists(module: str, name: str) -> bool:
    """A name without a dot: the module's own, a member of one of its classes, or a builtin."""
    loaded = importlib.import_module(module)
    classes = [value for value in vars(loaded).values() if isinstance(value, type)]
    return (hasattr(loaded, name) or hasattr(builtins, name)
            or any(hasattr(cls, name) or name in getattr(cls, "__dataclass_fields__", {}) for cls in classes))


def _references() -> list[tuple[str, str, str]]:
    found = []
    for module, path in sorted(modules().items()):
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            text = node.value.value if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) else None
            if isinstance(text, str):
                for kind, name in REFERENCE.findall(text):
                    if name.startswith("."):
                        dots = len(name) - len(name.lstrip("."))
                        base = package.split(".")
                        name = ".".join(base[: len(base) - (dots - 1)] + [name.lstrip(".")])
                    found.append((module, kind, name))
    return sorted(set(found))


def test_there_are_references_to_check() -> None:
    assert len(_references()) > 200


def test_every_docstring_reference_resolves() -> None:
    broken = [f"{module}: :{kind}:`{name}`" for module, kind, name in _references()
              if not (_exists(name) or ("." not in name and _bare_name_exists(module, name))
                      or _exists(f"{module}.{name}"))]
    assert broken == []


@pytest.mark.parametrize("name, exists", [("simrig.scoring.hota", True), ("simrig.trackers.saga.saga", True),
                                          ("simrig.trackers.cost_model", False), ("simrig.types.Track.no_such", False)])
def test_the_resolver(name: str, exists: bool) -> None:
    assert _exists(name) is exists
