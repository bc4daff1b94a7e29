"""Rooms a newcomer can hold in their head: no function in simrig's packages longer than 80 lines and no class
with more than 20 methods (read from the source's syntax tree, docstrings included)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("simrig", "tracker", "scenarios")
MAX_FUNCTION_LINES = 80
MAX_METHODS = 20


def _definitions():
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                yield path.relative_to(ROOT), node


def test_no_function_is_longer_than_80_lines():
    long = [f"{path}:{node.lineno} {node.name} ({node.end_lineno - node.lineno + 1} lines)"
            for path, node in _definitions() if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]
    assert long == []


def test_no_class_has_more_than_20_methods():
    big = [f"{path}:{node.lineno} {node.name} ({count} methods)" for path, node in _definitions()
           if isinstance(node, ast.ClassDef)
           and (count := sum(isinstance(b, (ast.FunctionDef, ast.AsyncFunctionDef)) for b in node.body)) > MAX_METHODS]
    assert big == []
