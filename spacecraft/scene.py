"""Scenes: one question a user asks flexsat, read from TOML or given as a dict, and validated.

A scene names the hub, the appendages (their truth model and their design model) and mounts, the
fidelity of the truth model, the controllers to tune, the manoeuvre, the outputs wanted, the FMUs
to export and the report to write. :func:`load_scene` reads a TOML file (or a dict, or a path)
into a :class:`Scene`, checking every key once, at the boundary: unknown keys, wrong types,
missing required values, non-positive or NaN physical values and outputs the scene cannot produce
raise :class:`SceneError` naming the file, the key path (``appendages[1].beam.diameter``) and the
problem. Inside a Scene every value is in SI units (angles in rad); the file uses degrees for
angles and Hz for the sample rate, as engineers write them.

Keys (units in the file; ``*`` required)

=====================================  =========  ==============================================
key                                    unit       meaning
=====================================  =========  ==============================================
``title``                              -          free text shown in the report
``hub.mass`` *                         kg         hub mass
``hub.inertia`` *                      kg m^2     hub inertia about its centre of mass
``appendages`` *                       -          array of tables, one per appendage (>= 1)
``appendages[i].name``                 -          identifier; default ``appendage<i+1>``
``appendages[i].position``             m          ``[x, y]`` of the attachment point in hub
                                                  axes, from the hub's centre of mass; [0, 0]
``appendages[i].direction``            deg        angle of the appendage's axis from hub +x, or
                                                  a vector ``[x, y]``; default 0
``appendages[i].truth``                -          ``"beam"`` (the distributed beam; default when
                                                  ``beam`` is given) or ``"chain"``
``appendages[i].design``               -          ``"fit"`` (chain fitted to the beam; default
                                                  with a beam), ``"chain"`` (the ``chain``
                                                  table; default without beam) or ``"truth"``
                                                  (the truth model itself)
``appendages[i].beam.section`` *       -          ``"rod"``, ``"tube"``, ``"rectangular"`` or
                                                  ``"uniform"``
``appendages[i].beam.length`` *        m          beam length
``appendages[i].beam.diameter``        m          rod: diameter
``appendages[i].beam.outer_diameter``  m          tube: outer diameter
``appendages[i].beam.wall_thickness``  m          tube: wall thickness
``appendages[i].beam.width``           m          rectangular: width
``appendages[i].beam.thickness``       m          rectangular: thickness (in the bending plane)
``appendages[i].beam.density``         kg/m^3     rod, tube, rectangular: material density
``appendages[i].beam.youngs_modulus``  Pa         rod, tube, rectangular: Young's modulus
``appendages[i].beam.bending_stiffness``  N m^2   uniform: EJ
``appendages[i].beam.linear_density``  kg/m       uniform: mass per length
``appendages[i].beam.damping_ratio``   -          modal damping ratio in [0, 1); default 0
``appendages[i].truth_chain``          -          a separate truth chain (same keys as
                                                  ``chain``) when ``chain`` is the design model
``appendages[i].fit.n_bodies``         -          bodies of the fitted chain (>= 2); default 3
``appendages[i].fit.match``            -          ``"poles-and-zeros"`` (flexsat's fit),
                                                  ``"frequencies"`` (the paper's) or a list of
                                                  both (one design model per entry); default
                                                  ``["poles-and-zeros", "frequencies"]``
``appendages[i].chain.lengths``        m          explicit chain: body lengths
``appendages[i].chain.masses``         kg         body masses
``appendages[i].chain.inertias``       kg m^2     body inertias about their centres of mass
``appendages[i].chain.hinge_stiffnesses``  N m/rad  one per hinge
``appendages[i].chain.hinge_dampings``  N m s/rad  one per hinge; default 0
``appendages[i].chain.com_offsets``    m          centre of mass from each body's start
``appendages[i].chain.root``           -          ``"rigid"`` (default) or ``"hinged"``
``appendages[i].chain.from_beam``      -          instead of the arrays: ``"rfem"`` (rigid
                                                  finite elements of the beam) with
``appendages[i].chain.n_bodies``       -          its number of bodies (>= 2)
``appendages[i].chain.root_stiffness``  N m/rad   ``root = "hinged"`` with ``from_beam``: the
                                                  drive hinge between mount and first body
``appendages[i].chain.root_damping``   N m s/rad  its damping; default 0
``fidelity.n_modes``                   -          bending modes per truncated beam, or
``fidelity.tolerance``                 -          relative accuracy from which flexsat picks
                                                  n_modes (default 1e-3 when neither is given)
``fidelity.method``                    -          ``"craig-bampton"`` (default), ``"residual"``,
                                                  ``"free-free"``
``fidelity.bandwidth_factor``          -          frequencies up to this multiple of the
                                                  controller bandwidth must match; default 5
``fidelity.prune``                     -          drop modes the inputs cannot excite and the
                                                  outputs cannot see; default true
``controller`` *                       -          the controllers to tune (table)
``controller.types``                   -          list of ``"pd"``, ``"lqr"``; default: the
                                                  tables present (``["pd"]`` if none)
``controller.sample_rate``             Hz         digital controllers (zero-order hold); default
                                                  continuous
``controller.pd.natural_frequency``    rad/s      closed-loop natural frequency, or
``controller.pd.bandwidth``            rad/s      closed-loop -3 dB bandwidth
``controller.pd.damping``              -          closed-loop damping ratio; default 0.7
``controller.pd.roll_off``             rad/s      optional low-pass corner
``controller.pd.notch``                rad/s      optional notch, or ``"first_mode"``
``controller.lqr.attitude_weight`` *   1/rad^2    weight on theta^2
``controller.lqr.rate_weight``         s^2/rad^2  weight on omega^2; default 0
``controller.lqr.torque_weight`` *     1/(N m)^2  weight on torque^2
``controller.lqr.deflection_weight``   1/m^2      weight on each tip deflection (needs
                                                  ``outputs.tip_deflection``)
``controller.lqr.estimator_speed``     -          estimator / regulator bandwidth; default 3
``manoeuvre.slew_angle`` *             deg        slew angle (non-zero)
``manoeuvre.slew_time`` *              s          duration of the cycloidal slew profile
``manoeuvre.duration``                 s          simulated time; default 3 x slew_time
``manoeuvre.step``                     s          output step; default slew_time / 500 (the
                                                  controller's sample time when digital)
``manoeuvre.disturbance.input``        -          ``"disturbance_torque"`` [N m],
                                                  ``"force_x"``, ``"force_y"`` [N] or
                                                  ``"<name>_tip_force"`` [N]
``manoeuvre.disturbance.amplitude``    N, N m     pulse amplitude (non-zero)
``manoeuvre.disturbance.start``        s          pulse start; default 0
``manoeuvre.disturbance.length``       s          pulse length; default to the end
``outputs.tip_deflection``             -          tip-deflection outputs; default false
``outputs.root_loads``                 -          root force and moment outputs; default false
``outputs.exact_reference``            -          frequency-domain references through the exact
                                                  beam W(s) (Bode plot, exact-loop verdict);
                                                  default false; needs a beam truth
``export.fmu``                         -          export FMUs; default false
``export.systems``                     -          any of ``"plant"``, ``"controller"``,
                                                  ``"closed_loop"``; default all three
``export.reference_files``             -          FMI cross-check files; default true
``export.step``                        s          FMU communication step; default manoeuvre
                                                  step
``report.plots``                       -          true (all), false, or a list of ``"slew"``,
                                                  ``"bode"``, ``"pole_zero"``; default false
``report.equivalence``                 -          equivalence table of fitted chains; default
                                                  true when a chain is fitted
=====================================  =========  ==============================================

References
----------
.. [1] TOML v1.0.0, https://toml.io/en/v1.0.0 (read with :mod:`tomllib`).
.. [2] Belonozhko et al. 2009 (PAPER.md): the default scene's steel rod.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from appendages.interface import FlexsatError

__all__ = [
    "SceneError",
    "Scene",
    "HubSpec",
    "BeamSpec",
    "ChainSpec",
    "FitSpec",
    "AppendageSpec",
    "FidelitySpec",
    "PDSpec",
    "LQRSpec",
    "ControllerSpec",
    "DisturbanceSpec",
    "ManoeuvreSpec",
    "OutputsSpec",
    "ExportSpec",
    "ReportSpec",
    "load_scene",
    "default_scene",
    "example_scenes",
    "scene_path",
]

PLOTS = ("slew", "bode", "pole_zero")
EXPORTABLE = ("plant", "controller", "closed_loop")
SECTIONS = ("rod", "tube", "rectangular", "uniform")
MATCHES = ("poles-and-zeros", "frequencies")
METHODS = ("craig-bampton", "residual", "free-free")
CONTROLLERS = ("pd", "lqr")


class SceneError(FlexsatError, ValueError):
    """A scene that cannot be run: names the file, the key path and the problem."""


# ---------------------------------------------------------------------------------------------
# the validated scene (SI units inside)
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class HubSpec:
    """Hub: mass [kg], inertia about its centre of mass [kg m^2]."""

    mass: float
    inertia: float


@dataclasses.dataclass(frozen=True)
class BeamSpec:
    """A uniform beam by section and material (SI units; see the module table)."""

    section: str
    length: float
    dimensions: tuple          # (key, value) pairs: section dimensions [m], or EJ [N m^2] and
    #                            rho*A [kg/m] for "uniform"
    density: float | None      # kg/m^3
    youngs_modulus: float | None  # Pa
    damping_ratio: float

    def build(self):
        """The :class:`appendages.Beam`."""
        from appendages import Beam

        d, z = dict(self.dimensions), self.damping_ratio
        if self.section == "rod":
            return Beam.circular_rod(self.length, d["diameter"], self.density,
                                     self.youngs_modulus, damping_ratio=z)
        if self.section == "tube":
            return Beam.tube(self.length, d["outer_diameter"], d["wall_thickness"], self.density,
                             self.youngs_modulus, damping_ratio=z)
        if self.section == "rectangular":
            return Beam.rectangular(self.length, d["width"], d["thickness"], self.density,
                                    self.youngs_modulus, damping_ratio=z)
        return Beam(self.length, d["bending_stiffness"], d["linear_density"], damping_ratio=z)


@dataclasses.dataclass(frozen=True)
class ChainSpec:
    """A hinged chain: explicit arrays, or rigid finite elements of the appendage's beam."""

    root: str = "rigid"
    lengths: tuple | None = None
    masses: tuple | None = None
    inertias: tuple | None = None
    hinge_stiffnesses: tuple | None = None
    hinge_dampings: tuple | None = None
    com_offsets: tuple | None = None
    from_beam: str | None = None
    n_bodies: int | None = None
    root_stiffness: float | None = None
    root_damping: float = 0.0


@dataclasses.dataclass(frozen=True)
class FitSpec:
    """Chain fit: number of bodies and one or more matching criteria."""

    n_bodies: int = 3
    match: tuple = MATCHES


@dataclasses.dataclass(frozen=True)
class AppendageSpec:
    """One mounted appendage: name, mount (position [m], direction [rad]) and its models."""

    name: str
    position: tuple
    direction: float
    truth: str
    design: str
    beam: BeamSpec | None
    chain: ChainSpec | None
    fit: FitSpec | None
    truth_chain: ChainSpec | None = None


@dataclasses.dataclass(frozen=True)
class FidelitySpec:
    """Truth-model fidelity: a fixed n_modes, or a tolerance from which n_modes is chosen."""

    n_modes: int | None = None
    tolerance: float | None = 1e-3
    method: str = "craig-bampton"
    bandwidth_factor: float = 5.0
    prune: bool = True


@dataclasses.dataclass(frozen=True)
class PDSpec:
    """PD specification (rad/s, damping ratio)."""

    natural_frequency: float | None = None
    bandwidth: float | None = None
    damping: float = 0.7
    roll_off: float | None = None
    notch: float | str | None = None


@dataclasses.dataclass(frozen=True)
class LQRSpec:
    """LQR weights (1/rad^2, s^2/rad^2, 1/(N m)^2, 1/m^2) and estimator speed ratio."""

    attitude_weight: float
    torque_weight: float
    rate_weight: float = 0.0
    deflection_weight: float | None = None
    estimator_speed: float = 3.0


@dataclasses.dataclass(frozen=True)
class ControllerSpec:
    """Controllers to tune on the design model and their sample time [s] (None: continuous)."""

    types: tuple
    pd: PDSpec | None
    lqr: LQRSpec | None
    sample_time: float | None = None


@dataclasses.dataclass(frozen=True)
class DisturbanceSpec:
    """A rectangular pulse on a plant disturbance input (N or N m), from start [s] for length [s]."""

    input: str
    amplitude: float
    start: float = 0.0
    length: float | None = None


@dataclasses.dataclass(frozen=True)
class ManoeuvreSpec:
    """Slew of slew_angle [rad] in slew_time [s], simulated for duration [s] at step [s]."""

    slew_angle: float
    slew_time: float
    duration: float
    step: float
    disturbance: DisturbanceSpec | None = None


@dataclasses.dataclass(frozen=True)
class OutputsSpec:
    """Which outputs to build: tip deflections, root loads, exact-beam references."""

    tip_deflection: bool = False
    root_loads: bool = False
    exact_reference: bool = False


@dataclasses.dataclass(frozen=True)
class ExportSpec:
    """FMU export: whether, which systems, cross-check files, communication step [s]."""

    fmu: bool = False
    systems: tuple = EXPORTABLE
    reference_files: bool = True
    step: float | None = None


@dataclasses.dataclass(frozen=True)
class ReportSpec:
    """Plots wanted and whether to tabulate the equivalence criterion."""

    plots: tuple = ()
    equivalence: bool = True


@dataclasses.dataclass(frozen=True)
class Scene:
    """A validated scene (SI units). Build it with :func:`load_scene` or :func:`default_scene`."""

    title: str
    source: str
    hub: HubSpec
    appendages: tuple
    fidelity: FidelitySpec
    controller: ControllerSpec
    manoeuvre: ManoeuvreSpec | None
    outputs: OutputsSpec
    export: ExportSpec
    report: ReportSpec

    def replace(self, **changes) -> "Scene":
        """A copy with some top-level parts replaced (e.g. ``export=ExportSpec(fmu=False)``)."""
        return dataclasses.replace(self, **changes)

    @property
    def has_beam_truth(self) -> bool:
        """True if some appendage's truth model is a distributed beam."""
        return any(a.truth == "beam" for a in self.appendages)

    @property
    def design_variants(self) -> tuple:
        """Labels of the design models: one per fit criterion (or ``("design",)``)."""
        matches: list = []
        for a in self.appendages:
            if a.design == "fit":
                for m in a.fit.match:
                    if m not in matches:
                        matches.append(m)
        return tuple(matches) if matches else ("design",)


# ---------------------------------------------------------------------------------------------
# the reader
# ---------------------------------------------------------------------------------------------
_MISSING = object()


class _Reader:
    """Pops keys off a table, checking types, and reports problems with file and key path."""

    def __init__(self, source: str):
        self.source = source

    def error(self, path: str, problem: str) -> SceneError:
        where = f"{self.source}: " if self.source else ""
        return SceneError(f"{where}{path}: {problem}" if path else f"{where}{problem}")

    def table(self, data, path: str) -> dict:
        if not isinstance(data, Mapping):
            raise self.error(path, f"must be a table; got {_kind(data)}")
        return dict(data)

    def done(self, table: dict, path: str, allowed) -> None:
        if table:
            key = sorted(table)[0]
            full = f"{path}.{key}" if path else key
            raise self.error(full, "unknown key; expected one of " + ", ".join(sorted(allowed)))

    def take(self, table: dict, key: str, path: str, default=_MISSING):
        full = f"{path}.{key}" if path else key
        if key not in table:
            if default is _MISSING:
                raise self.error(full, "missing required value")
            return default, full
        return table.pop(key), full

    def number(self, table: dict, key: str, path: str, unit: str, *, default=_MISSING,
               positive: bool = True, allow_zero: bool = False, upper: float | None = None,
               nonzero: bool = False):
        value, full = self.take(table, key, path, default)
        if value is default and default is not _MISSING:
            return value
        return self.check_number(value, full, unit, positive=positive, allow_zero=allow_zero,
                                 upper=upper, nonzero=nonzero)

    def check_number(self, value, full: str, unit: str, *, positive: bool = True,
                     allow_zero: bool = False, upper: float | None = None,
                     nonzero: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(full, f"must be a number [{unit}]; got {_kind(value)}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(full, f"must be finite [{unit}]; got {value!r}")
        if positive and (value < 0 or (value == 0 and not allow_zero)):
            what = "non-negative" if allow_zero else "positive"
            raise self.error(full, f"must be {what} [{unit}]; got {value!r}")
        if nonzero and value == 0:
            raise self.error(full, f"must be non-zero [{unit}]; got 0")
        if upper is not None and value >= upper:
            raise self.error(full, f"must be below {upper:g} [{unit}]; got {value!r}")
        return value

    def integer(self, table: dict, key: str, path: str, *, minimum: int, default=_MISSING):
        value, full = self.take(table, key, path, default)
        if value is default and default is not _MISSING:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(full, f"must be an integer; got {_kind(value)}")
        if value < minimum:
            raise self.error(full, f"must be at least {minimum}; got {value}")
        return value

    def boolean(self, table: dict, key: str, path: str, default: bool) -> bool:
        value, full = self.take(table, key, path, default)
        if not isinstance(value, bool):
            raise self.error(full, f"must be true or false; got {_kind(value)}")
        return value

    def choice(self, table: dict, key: str, path: str, choices, default=_MISSING):
        value, full = self.take(table, key, path, default)
        if value is None and default is None:
            return None
        if not isinstance(value, str):
            raise self.error(full, f"must be a string, one of {_quoted(choices)}; got {_kind(value)}")
        if value not in choices:
            raise self.error(full, f"must be one of {_quoted(choices)}; got {value!r}")
        return value

    def choices(self, table: dict, key: str, path: str, choices, default) -> tuple:
        """A string or a list of strings from ``choices`` (no duplicates)."""
        value, full = self.take(table, key, path, default)
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, (list, tuple)):
            raise self.error(full, f"must be a string or a list of strings from "
                                   f"{_quoted(choices)}; got {_kind(value)}")
        out = []
        for k, item in enumerate(value):
            if not isinstance(item, str) or item not in choices:
                raise self.error(f"{full}[{k}]", f"must be one of {_quoted(choices)}; got {item!r}")
            if item in out:
                raise self.error(f"{full}[{k}]", f"{item!r} is listed twice")
            out.append(item)
        return tuple(out)

    def vector(self, table: dict, key: str, path: str, unit: str, *, default=_MISSING,
               size: int | None = None, positive: bool = True, allow_zero: bool = False):
        value, full = self.take(table, key, path, default)
        if value is default and default is not _MISSING:
            return value
        if not isinstance(value, (list, tuple)):
            raise self.error(full, f"must be an array of numbers [{unit}]; got {_kind(value)}")
        if size is not None and len(value) != size:
            raise self.error(full, f"must have {size} entries [{unit}]; got {len(value)}")
        if not value:
            raise self.error(full, f"must not be empty [{unit}]")
        return tuple(self.check_number(v, f"{full}[{k}]", unit, positive=positive,
                                       allow_zero=allow_zero) for k, v in enumerate(value))


def _kind(value) -> str:
    if isinstance(value, bool):
        return f"boolean {str(value).lower()}"
    if isinstance(value, (int, float)):
        return f"number {value!r}"
    if isinstance(value, str):
        return f"string {value!r}"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, (list, tuple)):
        return f"an array of {len(value)}"
    return type(value).__name__


def _quoted(choices) -> str:
    return ", ".join(repr(c) for c in choices)


_SECTION_KEYS = {
    "rod": ("diameter",),
    "tube": ("outer_diameter", "wall_thickness"),
    "rectangular": ("width", "thickness"),
    "uniform": ("bending_stiffness", "linear_density"),
}
_SECTION_UNITS = {"diameter": "m", "outer_diameter": "m", "wall_thickness": "m", "width": "m",
                  "thickness": "m", "bending_stiffness": "N*m^2", "linear_density": "kg/m"}


def _read_beam(r: _Reader, data, path: str) -> BeamSpec:
    t = r.table(data, path)
    section = r.choice(t, "section", path, SECTIONS)
    length = r.number(t, "length", path, "m")
    dims = {key: r.number(t, key, path, _SECTION_UNITS[key]) for key in _SECTION_KEYS[section]}
    density = youngs = None
    if section != "uniform":
        density = r.number(t, "density", path, "kg/m^3")
        youngs = r.number(t, "youngs_modulus", path, "Pa")
    damping = r.number(t, "damping_ratio", path, "-", default=0.0, allow_zero=True, upper=1.0)
    allowed = {"section", "length", "damping_ratio", *_SECTION_KEYS[section]}
    if section != "uniform":
        allowed |= {"density", "youngs_modulus"}
    for key in list(t):
        if key in _SECTION_UNITS or key in ("density", "youngs_modulus"):
            raise r.error(f"{path}.{key}", f"does not apply to section {section!r}; it needs "
                          + ", ".join(sorted(allowed - {'section'})))
    r.done(t, path, allowed)
    if section == "tube" and dims["wall_thickness"] > dims["outer_diameter"] / 2:
        raise r.error(f"{path}.wall_thickness", "must be at most outer_diameter/2 = "
                      f"{dims['outer_diameter'] / 2:g} [m]; got {dims['wall_thickness']:g}")
    return BeamSpec(section, length, tuple(dims.items()), density, youngs, damping)


_CHAIN_ARRAYS = {"lengths": "m", "masses": "kg", "inertias": "kg*m^2",
                 "hinge_stiffnesses": "N*m/rad", "hinge_dampings": "N*m*s/rad",
                 "com_offsets": "m"}


def _read_chain(r: _Reader, data, path: str, has_beam: bool) -> ChainSpec:
    t = r.table(data, path)
    root = r.choice(t, "root", path, ("rigid", "hinged"), default="rigid")
    if "from_beam" in t:
        from_beam = r.choice(t, "from_beam", path, ("rfem",))
        if not has_beam:
            raise r.error(f"{path}.from_beam", "needs a beam table in the same appendage")
        n_bodies = r.integer(t, "n_bodies", path, minimum=2)
        root_stiffness = None
        root_damping = 0.0
        if root == "hinged":
            root_stiffness = r.number(t, "root_stiffness", path, "N*m/rad")
            root_damping = r.number(t, "root_damping", path, "N*m*s/rad", default=0.0,
                                    allow_zero=True)
        r.done(t, path, {"root", "from_beam", "n_bodies"}
               | ({"root_stiffness", "root_damping"} if root == "hinged" else set()))
        return ChainSpec(root=root, from_beam=from_beam, n_bodies=n_bodies,
                         root_stiffness=root_stiffness, root_damping=root_damping)
    values = {}
    for key in ("lengths", "masses", "inertias", "hinge_stiffnesses"):
        values[key] = r.vector(t, key, path, _CHAIN_ARRAYS[key], allow_zero=key == "inertias")
    for key in ("hinge_dampings", "com_offsets"):
        values[key] = r.vector(t, key, path, _CHAIN_ARRAYS[key], default=None, allow_zero=True)
    n = len(values["lengths"])
    n_hinges = n - 1 if root == "rigid" else n
    for key, size in (("masses", n), ("inertias", n), ("hinge_stiffnesses", n_hinges),
                      ("hinge_dampings", n_hinges), ("com_offsets", n)):
        if values[key] is not None and len(values[key]) != size:
            what = "body" if size == n and key not in ("hinge_stiffnesses", "hinge_dampings") \
                else f"hinge (root = {root!r})"
            raise r.error(f"{path}.{key}", f"must have {size} entries, one per {what}; got "
                          f"{len(values[key])}")
    r.done(t, path, {"root", *_CHAIN_ARRAYS, "from_beam"})
    return ChainSpec(root=root, **values)


def _read_appendage(r: _Reader, data, path: str, index: int) -> AppendageSpec:
    t = r.table(data, path)
    name, full = r.take(t, "name", path, f"appendage{index + 1}")
    if not isinstance(name, str) or not name.isidentifier():
        raise r.error(full, f"must be an identifier (letters, digits, '_'); got {_kind(name)}")
    position = r.vector(t, "position", path, "m", default=(0.0, 0.0), size=2, positive=False)
    direction_value, full = r.take(t, "direction", path, 0.0)
    if isinstance(direction_value, (list, tuple)):
        vec = r.vector({"direction": direction_value}, "direction", path, "-", size=2,
                       positive=False)
        if vec[0] == 0 and vec[1] == 0:
            raise r.error(full, "must be a non-zero vector")
        direction = math.atan2(vec[1], vec[0])
    else:
        direction = math.radians(r.check_number(direction_value, full, "deg", positive=False))
    beam = _read_beam(r, t.pop("beam"), f"{path}.beam") if "beam" in t else None
    chain = (_read_chain(r, t.pop("chain"), f"{path}.chain", beam is not None)
             if "chain" in t else None)
    truth_chain = (_read_chain(r, t.pop("truth_chain"), f"{path}.truth_chain", beam is not None)
                   if "truth_chain" in t else None)
    if beam is None and chain is None:
        raise r.error(path, "needs a beam table or a chain table (or both)")
    truth = r.choice(t, "truth", path, ("beam", "chain"),
                     default="beam" if beam is not None else "chain")
    if truth == "beam" and beam is None:
        raise r.error(f"{path}.truth", "is 'beam' but the appendage has no beam table")
    if truth == "chain" and chain is None and truth_chain is None:
        raise r.error(f"{path}.truth", "is 'chain' but the appendage has no chain table")
    if truth_chain is not None and truth != "chain":
        raise r.error(f"{path}.truth_chain", "applies to truth = 'chain' only")
    design = r.choice(t, "design", path, ("fit", "chain", "truth"),
                      default="fit" if beam is not None and truth == "beam" else
                      ("chain" if chain is not None else "truth"))
    fit = None
    if design == "fit":
        if beam is None:
            raise r.error(f"{path}.design", "is 'fit' but there is no beam table to fit")
        ft = r.table(t.pop("fit", {}), f"{path}.fit")
        n_bodies = r.integer(ft, "n_bodies", f"{path}.fit", minimum=2, default=3)
        match = r.choices(ft, "match", f"{path}.fit", MATCHES, default=list(MATCHES))
        if not match:
            raise r.error(f"{path}.fit.match", "must name at least one criterion")
        r.done(ft, f"{path}.fit", {"n_bodies", "match"})
        fit = FitSpec(n_bodies, match)
    elif "fit" in t:
        raise r.error(f"{path}.fit", f"applies to design = 'fit' only; design is {design!r}")
    if design == "chain" and chain is None:
        raise r.error(f"{path}.design", "is 'chain' but the appendage has no chain table")
    r.done(t, path, {"name", "position", "direction", "beam", "chain", "truth_chain", "truth",
                     "design", "fit"})
    return AppendageSpec(name, position, direction, truth, design, beam, chain, fit, truth_chain)


def _read_controller(r: _Reader, data, path: str) -> ControllerSpec:
    t = r.table(data, path)
    present = tuple(c for c in CONTROLLERS if c in t)
    types = r.choices(t, "types", path, CONTROLLERS, default=list(present or ("pd",)))
    if not types:
        raise r.error(f"{path}.types", "must name at least one controller")
    rate = r.number(t, "sample_rate", path, "Hz", default=None)
    pd_spec = lqr_spec = None
    if "pd" in types:
        p = f"{path}.pd"
        pt = r.table(t.pop("pd", {}), p)
        wn = r.number(pt, "natural_frequency", p, "rad/s", default=None)
        wb = r.number(pt, "bandwidth", p, "rad/s", default=None)
        if (wn is None) == (wb is None):
            raise r.error(p, "give exactly one of natural_frequency [rad/s] or bandwidth [rad/s]")
        damping = r.number(pt, "damping", p, "-", default=0.7)
        roll_off = r.number(pt, "roll_off", p, "rad/s", default=None)
        notch_value, full = r.take(pt, "notch", p, None)
        if notch_value is not None and notch_value != "first_mode":
            notch_value = r.check_number(notch_value, full, "rad/s")
        r.done(pt, p, {"natural_frequency", "bandwidth", "damping", "roll_off", "notch"})
        pd_spec = PDSpec(wn, wb, damping, roll_off, notch_value)
    elif "pd" in t:
        raise r.error(f"{path}.pd", "is given but 'pd' is not in controller.types")
    if "lqr" in types:
        p = f"{path}.lqr"
        if "lqr" not in t:
            raise r.error(p, "missing: controller.types lists 'lqr' but there are no weights")
        lt = r.table(t.pop("lqr"), p)
        lqr_spec = LQRSpec(
            attitude_weight=r.number(lt, "attitude_weight", p, "1/rad^2"),
            torque_weight=r.number(lt, "torque_weight", p, "1/(N*m)^2"),
            rate_weight=r.number(lt, "rate_weight", p, "s^2/rad^2", default=0.0, allow_zero=True),
            deflection_weight=r.number(lt, "deflection_weight", p, "1/m^2", default=None,
                                       allow_zero=True),
            estimator_speed=r.number(lt, "estimator_speed", p, "-", default=3.0))
        r.done(lt, p, {"attitude_weight", "torque_weight", "rate_weight", "deflection_weight",
                       "estimator_speed"})
    elif "lqr" in t:
        raise r.error(f"{path}.lqr", "is given but 'lqr' is not in controller.types")
    r.done(t, path, {"types", "sample_rate", "pd", "lqr"})
    return ControllerSpec(types, pd_spec, lqr_spec, None if rate is None else 1.0 / rate)


def _read_manoeuvre(r: _Reader, data, path: str, names, sample_time) -> ManoeuvreSpec:
    t = r.table(data, path)
    angle = math.radians(r.number(t, "slew_angle", path, "deg", positive=False, nonzero=True))
    slew_time = r.number(t, "slew_time", path, "s")
    duration = r.number(t, "duration", path, "s", default=3.0 * slew_time)
    default_step = sample_time if sample_time is not None else slew_time / 500.0
    step = r.number(t, "step", path, "s", default=default_step)
    if sample_time is not None and not math.isclose(step, sample_time, rel_tol=1e-9):
        raise r.error(f"{path}.step", f"must equal the controller's sample time "
                      f"1/sample_rate = {sample_time:g} s for a digital controller; got {step:g}")
    if duration < 2 * step:
        raise r.error(f"{path}.duration", f"must cover at least two steps ({2 * step:g} s); "
                      f"got {duration:g}")
    disturbance = None
    if "disturbance" in t:
        p = f"{path}.disturbance"
        dt_ = r.table(t.pop("disturbance"), p)
        inputs = ("disturbance_torque", "force_x", "force_y", *(f"{n}_tip_force" for n in names))
        disturbance = DisturbanceSpec(
            input=r.choice(dt_, "input", p, inputs),
            amplitude=r.number(dt_, "amplitude", p, "N", positive=False, nonzero=True),
            start=r.number(dt_, "start", p, "s", default=0.0, allow_zero=True),
            length=r.number(dt_, "length", p, "s", default=None))
        r.done(dt_, p, {"input", "amplitude", "start", "length"})
    r.done(t, path, {"slew_angle", "slew_time", "duration", "step", "disturbance"})
    return ManoeuvreSpec(angle, slew_time, duration, step, disturbance)


def _read_scene(data: Mapping, source: str) -> Scene:
    r = _Reader(source)
    t = r.table(data, "")
    title, full = r.take(t, "title", "", "")
    if not isinstance(title, str):
        raise r.error(full, f"must be a string; got {_kind(title)}")
    ht = r.table(r.take(t, "hub", "")[0], "hub")
    hub = HubSpec(r.number(ht, "mass", "hub", "kg"), r.number(ht, "inertia", "hub", "kg*m^2"))
    r.done(ht, "hub", {"mass", "inertia"})
    items, full = r.take(t, "appendages", "")
    if not isinstance(items, (list, tuple)) or not items:
        raise r.error(full, "must be a non-empty array of tables ([[appendages]])")
    appendages = tuple(_read_appendage(r, item, f"appendages[{k}]", k)
                       for k, item in enumerate(items))
    names = [a.name for a in appendages]
    for k, name in enumerate(names):
        if name in names[:k]:
            raise r.error(f"appendages[{k}].name", f"{name!r} is used twice")

    ft = r.table(t.pop("fidelity", {}), "fidelity")
    n_modes = r.integer(ft, "n_modes", "fidelity", minimum=1, default=None)
    tolerance = r.number(ft, "tolerance", "fidelity", "-", default=None, upper=1.0)
    if n_modes is not None and tolerance is not None:
        raise r.error("fidelity", "give n_modes or tolerance, not both")
    if n_modes is None and tolerance is None:
        tolerance = 1e-3
    fidelity = FidelitySpec(
        n_modes=n_modes, tolerance=tolerance,
        method=r.choice(ft, "method", "fidelity", METHODS, default="craig-bampton"),
        bandwidth_factor=r.number(ft, "bandwidth_factor", "fidelity", "-", default=5.0),
        prune=r.boolean(ft, "prune", "fidelity", True))
    r.done(ft, "fidelity", {"n_modes", "tolerance", "method", "bandwidth_factor", "prune"})

    controller = _read_controller(r, r.take(t, "controller", "")[0], "controller")
    manoeuvre = None
    if "manoeuvre" in t:
        manoeuvre = _read_manoeuvre(r, t.pop("manoeuvre"), "manoeuvre", names,
                                    controller.sample_time)

    ot = r.table(t.pop("outputs", {}), "outputs")
    outputs = OutputsSpec(r.boolean(ot, "tip_deflection", "outputs", False),
                          r.boolean(ot, "root_loads", "outputs", False),
                          r.boolean(ot, "exact_reference", "outputs", False))
    r.done(ot, "outputs", {"tip_deflection", "root_loads", "exact_reference"})

    et = r.table(t.pop("export", {}), "export")
    export = ExportSpec(fmu=r.boolean(et, "fmu", "export", False),
                        systems=r.choices(et, "systems", "export", EXPORTABLE,
                                          default=list(EXPORTABLE)),
                        reference_files=r.boolean(et, "reference_files", "export", True),
                        step=r.number(et, "step", "export", "s", default=None))
    r.done(et, "export", {"fmu", "systems", "reference_files", "step"})

    rt = r.table(t.pop("report", {}), "report")
    plots_value, full = r.take(rt, "plots", "report", False)
    if isinstance(plots_value, bool):
        plots = PLOTS if plots_value else ()
    else:
        plots = r.choices({"plots": plots_value}, "plots", "report", PLOTS, default=())
    equivalence = r.boolean(rt, "equivalence", "report", True)
    r.done(rt, "report", {"plots", "equivalence"})
    r.done(t, "", {"title", "hub", "appendages", "fidelity", "controller", "manoeuvre",
                   "outputs", "export", "report"})

    # outputs the scene cannot produce
    if outputs.exact_reference and not any(a.truth == "beam" for a in appendages):
        raise r.error("outputs.exact_reference", "needs an appendage whose truth is a "
                      "distributed beam (truth = 'beam'); this scene has only chains")
    if fidelity.n_modes is None and not any(a.truth == "beam" for a in appendages):
        fidelity = dataclasses.replace(fidelity, tolerance=None, n_modes=None)
    if "slew" in plots and manoeuvre is None:
        raise r.error("report.plots", "asks for 'slew' but the scene has no manoeuvre table")
    if (controller.lqr is not None and controller.lqr.deflection_weight is not None
            and not outputs.tip_deflection):
        raise r.error("controller.lqr.deflection_weight", "needs tip-deflection outputs: set "
                      "outputs.tip_deflection = true")
    if export.fmu and controller.sample_time is not None and (
            {"controller", "closed_loop"} & set(export.systems)):
        raise r.error("export.systems", "FMU export handles continuous-time systems only; a "
                      "digital controller (controller.sample_rate) cannot be exported: export "
                      "only 'plant' or remove sample_rate")
    if export.fmu and manoeuvre is None and export.step is None:
        raise r.error("export.step", "missing: without a manoeuvre table the FMU step must be "
                      "given [s]")
    return Scene(title=title, source=source or "<dict>", hub=hub, appendages=appendages,
                 fidelity=fidelity, controller=controller, manoeuvre=manoeuvre, outputs=outputs,
                 export=export, report=ReportSpec(plots, equivalence))


def load_scene(scene: "str | os.PathLike | Mapping[str, Any] | Scene | None" = None, *,
               source: str | None = None) -> Scene:
    """Read and validate a scene.

    Parameters
    ----------
    scene : path, dict, Scene or None
        A TOML file, a dict with the same structure (units of the file: deg, Hz), an already
        validated Scene (returned as is) or None for the embedded default scene.
    source : str, optional
        Name used in error messages for a dict (default ``"<dict>"``).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Naming the file, the key path and the problem (also for a missing file or bad TOML).
    """
    if isinstance(scene, Scene):
        return scene
    if scene is None:
        return default_scene()
    if isinstance(scene, Mapping):
        return _read_scene(scene, source or "<dict>")
    if not isinstance(scene, (str, os.PathLike)):
        raise SceneError(f"scene must be a TOML file path, a dict or a Scene; got "
                         f"{type(scene).__name__}")
    path = Path(scene)
    try:
        text = path.read_bytes()
    except FileNotFoundError:
        raise SceneError(f"{path}: no such scene file") from None
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file ({exc.strerror})") from None
    try:
        data = tomllib.loads(text.decode("utf-8"))
    except UnicodeDecodeError:
        raise SceneError(f"{path}: not a UTF-8 text file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: invalid TOML ({exc})") from None
    return _read_scene(data, source or str(path))


def scene_path(name: str) -> Path:
    """Path of an embedded scene (``"default"``, ``"single_boom"``, ``"two_wings"``...)."""
    resource = importlib.resources.files("spacecraft").joinpath("scenes", f"{name}.toml")
    path = Path(str(resource))
    if not path.is_file():
        raise SceneError(f"no embedded scene {name!r}; available: "
                         + ", ".join(example_scenes()))
    return path


def example_scenes() -> list[str]:
    """Names of the embedded scenes."""
    folder = Path(str(importlib.resources.files("spacecraft").joinpath("scenes")))
    return sorted(p.stem for p in folder.glob("*.toml"))


def default_scene() -> Scene:
    """The embedded default scene: the paper's steel rod on a 100 kg, 50 kg m^2 hub."""
    path = scene_path("default")
    return load_scene(path, source="default scene")
