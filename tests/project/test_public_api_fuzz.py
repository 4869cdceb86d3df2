"""Every public function and class refuses a bad argument by the parameter's name.

The callables are discovered, not listed: every function and class in ``__all__`` of
appendages, controllers, fmu, spacecraft and its subpackages basilisk and sweep (so a function
added later is fuzzed too: a required parameter this file has no valid value for fails the test
until one is added to :data:`VALID`). Plain dataclasses without ``__post_init__`` are records
flexsat returns (margins, results, layouts); their fields are not checked inputs and they are
left out; :data:`SKIP` lists the few others, each with its reason.

Each parameter in turn gets each of the 16 values of :data:`BAD` (NaN, infinities, negative,
zero, huge, subnormal, complex, a bool, a string, None, empty and NaN-holding sequences, an
arbitrary object), every other parameter its valid value (its default, or
:data:`VALID`). A call passes if it returns without a NaN in a numeric result (a legal value
accepted: None for an optional parameter, -1 for a signed one), or raises ValueError,
TypeError, one of flexsat's errors or FileNotFoundError whose message names the parameter (as
a word, or as the last part of a scene key), or a FloatingPointError or one of flexsat's
ArithmeticErrors (a response that leaves the float64 range, a Basilisk run that diverges:
raised on purpose, saying so); it fails on any other exception, a message that does not name
the parameter, a NaN in the result, or a call longer than :data:`TIMEOUT`. The table is fixed
(derandomised): the same calls on every machine.

``python tests/project/test_public_api_fuzz.py`` prints the calls that fail, and their count.
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import importlib
import inspect
import math
import re
import signal
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from fuzzing import BAD
from plants import modal_plant

#: Packages whose ``__all__`` is the public API fuzzed here.
PACKAGES = ("appendages", "controllers", "fmu", "spacecraft", "spacecraft.basilisk",
            "spacecraft.sweep")
#: Callables not fuzzed, and why.
SKIP = {
    "spacecraft.sweep.sweep": "each call starts a Dask cluster (tests/spacecraft/sweep/test_sweep_*.py)",
    "spacecraft.sweep.run_sweep": "each call starts a Dask cluster (tests/spacecraft/sweep/test_sweep_*.py)",
    "appendages.Appendage": "a typing Protocol",
    "appendages.FiniteAppendage": "a typing Protocol",
    "appendages.interface.ThreeAxisAppendage": "a typing Protocol",
    "fmu.Signal": "a typing alias (a float or a function of time)",
    "appendages.read_nastran": "needs a NASTRAN OP2 file and the optional pyNastran "
                               "(tests/appendages/test_nastran*.py)",
}
#: Callables whose valid call costs much (FMU builds, co-simulations, scene runs, Basilisk):
#: fuzzed in the slow test.
EXPENSIVE = {"fmu.export", "fmu.cosimulate", "fmu.write_ssp", "fmu.cosimulate_ssp",
             "spacecraft.run", "spacecraft.write_report", "spacecraft.default_scene", "spacecraft.sweep.load_sweep",
             "spacecraft.basilisk.simulate", "spacecraft.basilisk.simulate_slew",
             "spacecraft.basilisk.slew_comparison", "spacecraft.basilisk.linear_slew",
             "spacecraft.basilisk.linearised",
             "appendages.fit_chain", "appendages.fit_chain_3d", "appendages.criterion",
             "controllers.compare", "controllers.assert_closed_loops_close",
             "controllers.lqr", "controllers.lqr_design"}
#: Callables that run Basilisk (the optional basilisk extra, not in the test install): fuzzed
#: by the test marked ``basilisk`` only (CI's Basilisk pass; skipped, saying why, without bsk).
NEEDS_BASILISK = {"spacecraft.basilisk.require_basilisk", "spacecraft.basilisk.simulate",
                  "spacecraft.basilisk.simulate_slew", "spacecraft.basilisk.slew_comparison",
                  "spacecraft.basilisk.linearised"}
#: Longest call [s] before it counts as a failure (work not estimated before it is done).
TIMEOUT = 20.0


# -------------------------------------------------------------------------------------------
# valid values of required parameters: "package.name.parameter", else "parameter"
# -------------------------------------------------------------------------------------------
J = 50.0


@functools.cache
def _objects() -> dict:
    import control

    import controllers
    from appendages import Beam, HingedChain
    from spacecraft import Hub, Mount, Spacecraft

    plant = modal_plant(J, [(2.0, 0.005, 0.04, 0.04)], tips=[("wing_tip_deflection", [0.5])])
    pd = controllers.pd(plant, natural_frequency=0.5)
    loop = controllers.close_loop(plant, pd)
    response = controllers.slew(loop, 0.1, 10.0, t_final=20.0)
    beam = Beam(2.0, 100.0, 1.0)
    tube = Beam.tube(2.0, 0.05, 0.001, 1600.0, 1.2e11)
    chain = HingedChain([1.0, 1.0], [1.0, 1.0], [0.1, 0.1], [100.0])
    spacecraft = Spacecraft(Hub(100.0, J), [Mount(chain, (0.5, 0.0), 0.0, name="wing")])
    design = spacecraft.plant(tip_deflection=True)
    digital = controllers.pd(design, natural_frequency=0.5, sample_time=0.1)
    rods = [beam.root_model(n) for n in (2,)] if hasattr(beam, "root_model") else []
    return dict(plant=plant, pd=pd, loop=loop, response=response, beam=beam, tube=tube,
                chain=chain, spacecraft=spacecraft, design=design, digital=digital,
                system=control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]], inputs=["u"],
                                  outputs=["y"]), rods=rods)


class Lazy:
    """A valid value built when first needed (an FMU, a scene's run)."""

    def __init__(self, build):
        self.build = functools.cache(build)


def _fmus(tmp: Path) -> dict:
    import fmu

    o = _objects()
    plant = fmu.export(o["plant"], tmp / "plant.fmu")
    controller = fmu.export(o["pd"], tmp / "controller.fmu")
    return {"plant": plant, "controller": controller,
            "ssp": fmu.write_ssp(tmp / "loop.ssp", plant, controller)}


def _folder(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    return path


def _modal_file(tmp: Path, appendage) -> Path:
    from appendages import write_modal_data

    write_modal_data(appendage, tmp / "modal.toml")
    return tmp / "modal.toml"


def _valid_table(tmp: Path) -> dict:
    import control

    import controllers
    from appendages import ModalAppendage, RootModel
    from spacecraft import Hub

    o = _objects()
    step = controllers.step_reference(0.1, 10.0)
    rigid = RootModel(np.eye(1), np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1)), ("q",),
                      n_root=1)
    fmus = Lazy(lambda: _fmus(tmp))
    wheel = controllers.ReactionWheel(0.5, 20.0)
    modal = ModalAppendage([3.0, 20.0], [[0.5, 0.4], [0.2, -0.1]], [[1.0, 1.0], [1.0, 4.0 / 3.0]],
                           length=2.0)
    return {
        # appendages
        "length": 2.0, "bending_stiffness": 100.0, "linear_density": 1.0,
        "lengths": [1.0, 1.0], "masses": [1.0, 1.0], "inertias": [0.1, 0.1],
        "hinge_stiffnesses": [100.0], "stiffness": 100.0, "n_modes": 2, "n": 3,
        "appendages.Rod.inertia": 1.0, "appendages.characteristic_roots.kind": "free-free",
        "beam": o["beam"], "appendages.fit_chain_3d.beam": o["tube"],
        "reference": o["beam"], "candidate": o["chain"], "tolerance": 1e-3,
        "frequencies": [3.0, 20.0], "participation": [[0.5, 0.4], [0.2, -0.1]],
        "rigid_mass": [[1.0, 1.0], [1.0, 4.0 / 3.0]],
        "xy": o["chain"].root_model(), "xz": o["chain"].root_model(),
        "appendages.write_modal_data.appendage": modal,
        "appendages.write_modal_data.path": tmp / "written.toml",
        "appendages.read_modal_data.path": Lazy(lambda: _modal_file(tmp, modal)),
        "torsion": rigid, "axial": rigid,
        "segments": [o["beam"], o["beam"]], "appendages.TipBody.inertia": 0.1,
        # controllers
        "plant": o["plant"], "controller": o["pd"], "closed_loop": o["loop"],
        "design_plant": o["plant"], "truth_plant": o["plant"], "response": o["response"],
        "controllers.nyquist_count.truth_plant": Lazy(
            lambda: control.frd(o["plant"], np.logspace(-4.0, 4.0, 2000))),
        "controllers.nyquist_count.response": None,
        "controllers.assert_closed_loops_close.actual": o["loop"],
        "controllers.assert_closed_loops_close.expected": o["loop"],
        "controllers.assert_closed_loops_close.angle": 0.1, "controllers.compare.slew_time": 10.0,
        "spacecraft.basilisk.simulate.sample_time": 0.1,
        "controllers.assert_closed_loops_close.duration": 10.0,
        "actual": {"overshoot": 1.0}, "expected": {"overshoot": 1.0},
        "angle": 0.1, "duration": 10.0, "t": np.linspace(0.0, 20.0, 21), "T": np.linspace(
            0.0, 1.0, 11), "system": o["system"], "omega": np.logspace(-1.0, 1.0, 50),
        "loop": lambda w: 1.0 / (1j * np.asarray(w)) ** 2 * (1.0 + 2j * np.asarray(w)),
        "attitude_weight": 1.0, "rate_weight": 0.0, "torque_weight": 1.0,
        "torque_noise": 1.0, "attitude_noise": 1e-3, "rate_noise": 1e-3,
        "bandwidth": 1.0, "damping": 0.7, "natural_frequency": 1.0, "frequency": 1.0,
        "controllers.pd_gains.inertia": J,
        "controllers.principal_axes.inertia": np.diag([2.0, 3.0, 4.0]),
        "modes": [(2.0, 0.005)], "base": step, "shaper": controllers.zv_shaper(2.0),
        "controllers.pd.natural_frequency": 0.5, "controllers.Simulator.dt": 0.1,
        "controllers.reference_profile.duration": 10.0, "profile": step,
        "torque_limit": 0.5, "momentum_limit": 20.0, "amplitudes": [0.5, 0.5],
        "times": [0.0, 1.0], "controllers.WheelSet.wheels": [wheel],
        "wheels": controllers.WheelSet([wheel]), "controllers.check_slew_time.inertia": J,
        "controllers.shortest_slew_time.inertia": J,
        "noise": controllers.SensorNoise(attitude_density=1e-5, angle_random_walk=1e-6),
        "window": 1.0, "controllers.simulate_wheels.T": np.linspace(0.0, 1.0, 11),
        "controllers.manoeuvre_metrics.end_time": 10.0,
        "controllers.bang_coast_bang.duration": 10.0, "controllers.jerk_limited.duration": 10.0,
        "controllers.shaped.base": controllers.bang_coast_bang(0.1, 10.0),
        "controllers.minimum_time.kind": "bang-coast-bang",
        "controllers.reference_profile.kind": "step",
        "controllers.Profile.kind": step.kind, "breakpoints": step.breakpoints,
        "coefficients": step.coefficients,
        # fmu
        "path": tmp / "fuzz.fmu", "fmu.write_ssp.path": tmp / "fuzz.ssp",
        "spacecraft.output_folder.path": tmp / "fuzz_out", "name": "theta",
        "plant_fmu": Lazy(lambda: fmus.build()["plant"]),
        "controller_fmu": Lazy(lambda: fmus.build()["controller"]),
        "ssp": Lazy(lambda: fmus.build()["ssp"]), "stop_time": 1.0, "step": 0.01,
        "result": Lazy(lambda: _small_run()), "folder": Lazy(lambda: _folder(tmp / "report")),
        "spacecraft.scene_path.name": "default",
        # spacecraft
        "mass": 100.0, "spacecraft.Hub.inertia": J, "hub": Hub(100.0, J),
        "appendage": o["beam"], "spacecraft": o["spacecraft"],
        "spacecraft.basilisk.compare.response": o["response"],
        "spacecraft.basilisk.compare.reference": o["response"],
        "spacecraft.basilisk.default_sample_time.plant": o["design"],
        "spacecraft.basilisk.default_sample_time.controller": o["pd"],
        "spacecraft.basilisk.flight_software_law.controller": o["digital"],
        "spacecraft.basilisk.linear_slew.controller": o["digital"],
        "spacecraft.basilisk.simulate_slew.controller": o["digital"],
        "spacecraft.basilisk.slew_comparison.controller": o["digital"],
        "spacecraft.basilisk.basilisk_chain.chain": o["chain"],
        "spacecraft.basilisk.inextensible.chain": o["chain"],
        "spacecraft.basilisk.torsion_held.chain": o["chain"],
        "spacecraft.basilisk.torsion_frequency.chain": o["chain"], "sigma": [0.0, 0.0, 0.1],
        "spin_inertia": 0.1, "highest_frequency": 10.0, "sample_time": 0.1, "dt": 0.01,
        "n_bodies": 3, "slew_time": 10.0, "spacecraft.basilisk.simulate.duration": 1.0,
        "spacecraft.sweep.sweep_scene_path.name": "default",
    }


def _small_run():
    import spacecraft

    return spacecraft.run(SMALL_SCENE, time_responses=False)


#: A scene that runs in a fraction of a second: a 2-body chain, PD, no manoeuvre.
SMALL_SCENE = {
    "hub": {"mass": 100.0, "inertia": 50.0},
    "appendages": [{"name": "wing", "position": [0.5, 0.0], "chain": {
        "lengths": [1.0, 1.0], "masses": [1.0, 1.0], "inertias": [0.1, 0.1],
        "hinge_stiffnesses": [100.0]}}],
    "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.5}},
}


def public_callables() -> dict:
    """``"package.name" -> callable`` for every function and class of the public API."""
    found, seen = {}, set()
    for package in PACKAGES:
        module = importlib.import_module(package)
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.ismodule(obj) or not callable(obj) or id(obj) in seen:
                continue
            seen.add(id(obj))
            if inspect.isclass(obj) and (issubclass(obj, (BaseException, Warning)) or (
                    dataclasses.is_dataclass(obj) and not hasattr(obj, "__post_init__"))):
                continue
            found[f"{package}.{name}"] = obj
    return found


def _parameters(obj) -> list:
    return [p for p in inspect.signature(obj).parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]


def _baseline(qualname: str, obj, table: dict) -> dict:
    """Valid keyword values of the required parameters of ``obj``."""
    kwargs = {}
    for p in _parameters(obj):
        key = f"{qualname}.{p.name}"
        if p.default is not p.empty:
            if key in table:  # an optional parameter a valid call needs (one of two...)
                kwargs[p.name] = table[key]
            continue
        if key in table or p.name in table:
            value = table[key] if key in table else table[p.name]
            kwargs[p.name] = value if not isinstance(value, Lazy) else value
        else:
            raise LookupError(f"{qualname}: no valid value for its required parameter "
                              f"{p.name!r}: add one to VALID in tests/project/test_public_api_fuzz.py")
    return kwargs


def _call(obj, parameters, kwargs):
    positional = [kwargs.pop(p.name) for p in parameters if p.kind == p.POSITIONAL_ONLY
                  and p.name in kwargs]
    return obj(*positional, **kwargs)


@contextlib.contextmanager
def _deadline(seconds: float):
    def expired(signum, frame):
        raise TimeoutError(f"took longer than {seconds:g} s")
    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _has_nan(value) -> bool:
    if isinstance(value, (float, np.floating)):
        return math.isnan(value)
    if isinstance(value, np.ndarray) and value.dtype.kind in "fc":
        return bool(np.isnan(value).any())
    if isinstance(value, tuple) and len(value) <= 10:
        return any(_has_nan(v) for v in value)
    return False


def _names(message: str, name: str) -> bool:
    return re.search(rf"(?<![A-Za-z0-9]){re.escape(name)}(?![A-Za-z0-9])", message) is not None


def fuzz(qualname: str, obj, table: dict) -> tuple[int, list[str]]:
    """(calls, failures) of one callable over every parameter and bad value."""
    from appendages.interface import FlexsatError
    from fmu import FMUError

    parameters = _parameters(obj)
    base = {k: v.build() if isinstance(v, Lazy) else v
            for k, v in _baseline(qualname, obj, table).items()}
    calls, failures = 0, []
    for p in parameters:
        for bad in BAD:
            kwargs = dict(base)
            kwargs[p.name] = bad
            calls += 1
            what = f"{qualname}({p.name}={bad!r})"
            try:
                with warnings.catch_warnings(), np.errstate(all="ignore"), \
                        _deadline(TIMEOUT):
                    warnings.simplefilter("ignore")
                    result = _call(obj, parameters, kwargs)
            except (FloatingPointError, ArithmeticError) as exc:
                # a response that leaves the float64 range (FloatingPointError), a run that
                # diverges (BasiliskIntegrationError): raised on purpose, saying so
                if not isinstance(exc, (FloatingPointError, FlexsatError)):
                    failures.append(f"{what}: {type(exc).__name__}: {str(exc)[:160]}")
            except (ValueError, TypeError, FlexsatError, FMUError, FileNotFoundError) as exc:
                if not _names(str(exc), p.name):
                    failures.append(f"{what}: {type(exc).__name__} not naming it: "
                                    f"{str(exc)[:160]}")
            except Exception as exc:  # noqa: BLE001 - the finding is the exception's kind
                failures.append(f"{what}: {type(exc).__name__}: {str(exc)[:160]}")
            else:
                if _has_nan(result):
                    failures.append(f"{what}: returned NaN")
    return calls, failures


def _run(names, tmp) -> tuple[int, list[str]]:
    """Fuzz ``names``, each callable in a working folder of its own under ``tmp`` (a path
    such as 'x' that one accepts and writes must not be read by the next)."""
    import os

    table = _valid_table(Path(tmp))
    calls, failures = 0, []
    here = os.getcwd()
    try:
        for qualname, obj in public_callables().items():
            if qualname in SKIP or qualname not in names:
                continue
            folder = Path(tmp) / "cwd" / qualname  # each callable its own working folder
            folder.mkdir(parents=True)
            os.chdir(folder)
            n, bad = fuzz(qualname, obj, table)
            calls += n
            failures += bad
    finally:
        os.chdir(here)
    return calls, failures


def _selected(expensive: bool) -> set:
    return {q for q in public_callables()
            if q not in SKIP and q not in NEEDS_BASILISK and (q in EXPENSIVE) == expensive}


def _valid_call(qualname, obj, table):
    kwargs = {k: v.build() if isinstance(v, Lazy) else v
              for k, v in _baseline(qualname, obj, table).items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _call(obj, _parameters(obj), kwargs)


def test_every_public_callable_has_valid_values_for_its_required_parameters(tmp_path):
    """The fuzz's baseline: every callable has a valid value for each required parameter (a
    function added later without one fails here, naming the parameter), and the call with
    those values succeeds (for the cheap ones; the expensive ones in the slow test)."""
    table = _valid_table(tmp_path)
    missing = []
    for qualname, obj in public_callables().items():
        if qualname in SKIP:
            continue
        try:
            _baseline(qualname, obj, table)
        except LookupError as exc:
            missing.append(str(exc))
            continue
        if qualname not in EXPENSIVE and qualname not in NEEDS_BASILISK:
            try:
                _valid_call(qualname, obj, table)
            except Exception as exc:  # noqa: BLE001
                missing.append(f"{qualname}: its valid call fails: {type(exc).__name__}: {exc}")
    assert not missing, "\n".join(missing)
    assert set(SKIP) <= set(public_callables()) | {
        "appendages.Appendage", "appendages.FiniteAppendage",
        "appendages.interface.ThreeAxisAppendage", "fmu.Signal"} | (
        {"appendages.read_nastran"}), \
        "a SKIP entry names no public callable"


@pytest.mark.slow
def test_public_functions_refuse_bad_values_by_name(tmp_path):
    calls, failures = _run(_selected(expensive=False), tmp_path)
    assert calls > 3000
    assert not failures, f"{len(failures)} of {calls} calls:\n" + "\n".join(failures)


@pytest.mark.slow
def test_expensive_public_functions_refuse_bad_values_by_name(tmp_path):
    """FMU builds and co-simulations, scene runs and reports, Basilisk runs, fits: each valid
    call succeeds, and every bad value is refused by name (about a minute)."""
    table = _valid_table(tmp_path)
    for qualname in sorted(_selected(expensive=True)):
        _valid_call(qualname, public_callables()[qualname], table)
    calls, failures = _run(_selected(expensive=True), tmp_path)
    assert calls > 1500                             # Basilisk's runs apart (below)
    assert not failures, f"{len(failures)} of {calls} calls:\n" + "\n".join(failures)


@pytest.mark.slow
@pytest.mark.basilisk
def test_basilisk_runs_refuse_bad_values_by_name(tmp_path):
    """What runs Basilisk (NEEDS_BASILISK), where bsk is installed: each valid call succeeds,
    and every bad value is refused by name."""
    table = _valid_table(tmp_path)
    for qualname in sorted(NEEDS_BASILISK):
        _valid_call(qualname, public_callables()[qualname], table)
    calls, failures = _run(NEEDS_BASILISK, tmp_path)
    assert calls > 500
    assert not failures, f"{len(failures)} of {calls} calls:\n" + "\n".join(failures)


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        which = (set(public_callables()) if "--all" in sys.argv else
                 _selected("--expensive" in sys.argv))
        total, found = _run(which, folder)
    print("\n".join(found))
    print(f"{len(found)} of {total} calls fail")
