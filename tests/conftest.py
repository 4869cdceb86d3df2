"""Test-session set-up: every module of the four packages is imported before any test runs.

Hypothesis (6.170 here) draws about 5 % of its examples from the constants of the "local"
modules in sys.modules at the time of the draw (``_get_local_constants`` in
``hypothesis/internal/conjecture/providers.py``: modules outside the standard library and
site-packages, test files excluded), and it offers no setting to turn that off. With our
packages imported on demand, the pool, and so the examples of a ``derandomize=True`` test,
depended on which test files had run before it: the issue-9 review found ``test_lqr_fuzz``
failing after ``tests/project/test_extremes.py`` and passing alone. With every module of appendages,
controllers, fmu and spacecraft imported here, the pool is the same for any order or subset of
the tests (for a given version of the code), and the constants of our own modules (1e-13,
1e10, the documented limits...) stay in it: they are good fuzz inputs.
"""
import importlib
import importlib.util
import pathlib
import pkgutil
import sys

import pytest

PACKAGES = ("appendages", "controllers", "fmu", "spacecraft")

# The tests' shared helpers (tests/support: the independent reference models, plants, FMU
# cases and FMI tools, the test scenes: ``from scenes import scene_with``) import by name; a
# test module imports no other test module (tests/project/test_architecture.py).
TESTS = pathlib.Path(__file__).resolve().parent
if str(TESTS / "support") not in sys.path:
    sys.path.append(str(TESTS / "support"))


def _import_everything():
    for name in PACKAGES:
        package = importlib.import_module(name)
        # an optional dependency missing (e.g. Basilisk) leaves its adapter out, as it would
        # be out of every test run in that environment
        for module in pkgutil.walk_packages(package.__path__, f"{name}.",
                                            onerror=lambda _: None):
            try:
                importlib.import_module(module.name)
            except ImportError:
                pass


_import_everything()


def pytest_collection_modifyitems(config, items):
    """Tests marked ``basilisk`` run Basilisk (the optional ``basilisk`` extra): where bsk is not
    installed (the README's test install) they are skipped with the install hint as the reason.
    CI runs them in a pass of their own with the extra (``pytest -m basilisk``)."""
    if importlib.util.find_spec("Basilisk") is not None:
        return
    from spacecraft.basilisk import INSTALL_HINT
    skip = pytest.mark.skip(reason=INSTALL_HINT)
    for item in items:
        if item.get_closest_marker("basilisk") is not None:
            item.add_marker(skip)
