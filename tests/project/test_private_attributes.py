"""A private attribute (``obj._name``) is private to the module that defines it.

tests/project/test_architecture.py checks the imports; this checks the attribute accesses: a module
that reaches into another module's object for a private method or attribute (``beam._roots``)
depends on its internals as surely as a private import does. The check is by name: an access
``x._name`` (x not ``self`` or ``cls``) is allowed when the same module defines ``_name`` (a
function, method, class or an assignment to ``self._name``/``cls._name``), or it is one of the
public underscore methods of namedtuples or ``sys._getframe``.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NAMEDTUPLE = {"_replace", "_asdict", "_fields", "_make", "_field_defaults"}
STANDARD = {"_getframe"}  # sys._getframe: the standard library's documented function


def _private_definitions(tree: ast.AST) -> set:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            names.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
    return {n for n in names if n.startswith("_") and not n.startswith("__")}


def _foreign_private_accesses(path: Path) -> list:
    tree = ast.parse(path.read_text(), filename=str(path))
    defined = _private_definitions(tree)
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        name = node.attr
        if not name.startswith("_") or name.startswith("__") or name in NAMEDTUPLE | STANDARD:
            continue
        if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
            continue
        if name not in defined:
            found.append(f"{path.relative_to(ROOT)}:{node.lineno}: .{name}")
    return found


@pytest.mark.parametrize("package", ["appendages", "controllers", "fmu"])
@pytest.mark.slow
def test_no_private_attribute_of_another_module_is_used(package):
    found = [hit for path in sorted((ROOT / package).rglob("*.py"))
             for hit in _foreign_private_accesses(path)]
    assert not found, "private attributes of other modules used:\n" + "\n".join(found)
