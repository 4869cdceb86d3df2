"""The one-way dependencies between the four packages (DESIGN.md), checked on the sources."""

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("appendages", "spacecraft", "controllers", "fmu")
ALLOWED = {
    "appendages": set(),
    "controllers": set(),
    "fmu": set(),
    "spacecraft": {"appendages", "controllers", "fmu"},
}


def imported_packages(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found & set(PACKAGES)


@pytest.mark.parametrize("package", PACKAGES)
def test_package_imports_only_what_it_may(package):
    sources = sorted((ROOT / package).rglob("*.py"))
    assert sources, f"no sources found for {package}"
    for source in sources:
        illegal = imported_packages(source) - ALLOWED[package] - {package}
        assert not illegal, f"{source.relative_to(ROOT)} imports {sorted(illegal)}"


@pytest.mark.parametrize("package", PACKAGES)
def test_every_module_declares_all(package):
    for source in sorted((ROOT / package).rglob("*.py")):
        tree = ast.parse(source.read_text())
        names = {t.id for node in tree.body if isinstance(node, ast.Assign) for t in node.targets
                 if isinstance(t, ast.Name)}
        assert "__all__" in names, f"{source.relative_to(ROOT)} has no __all__"


def test_every_module_is_imported_before_the_tests_run():
    """tests/conftest.py imports every module of the packages, so that hypothesis's pool of
    constants from loaded modules (and so the examples of a derandomised test) is the same for
    any order or subset of the tests (issue-9 review: test_lqr_fuzz failed only after
    tests/test_extremes.py)."""
    import importlib
    import pkgutil
    import sys

    missing = []
    for name in ("appendages", "controllers", "fmu", "spacecraft"):
        package = importlib.import_module(name)
        for module in pkgutil.walk_packages(package.__path__, f"{name}.",
                                            onerror=lambda _: None):
            if module.name not in sys.modules:
                missing.append(module.name)
    assert not missing
