"""The scene's data model: a validated scene and its parts, in SI units (angles in rad).

:func:`spacecraft.scene.read.load_scene` builds a :class:`Scene` from a TOML file or a dict and checks
every value once; everything downstream (the runner, the report, the command line) reads these
frozen dataclasses. The keys of the file, their units and ranges are documented in
:mod:`spacecraft.scene.read`. :func:`scene_dict` gives the resolved scene (every default filled in)
as a JSON-ready dict for ``results.json``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
import warnings

import numpy as np

from .limits import Limits

__all__ = [
    "HubSpec", "TipSpec", "BeamSpec", "SteppedBeamSpec", "TaperedBeamSpec", "ModalSpec",
    "MODAL_SOURCES", "load_mass_matrix", "ChainSpec", "FitSpec", "AppendageSpec", "FidelitySpec", "PDSpec",
    "LQRSpec", "ControllerSpec", "DisturbanceSpec", "ManoeuvreSpec", "OutputsSpec", "ExportSpec",
    "ReportSpec", "ReactionWheelSpec", "SimulatorSpec", "ShaperSpec", "WheelsSpec",
    "SensorsSpec", "Scene", "scene_dict", "PLOTS",
    "PLOT_ALIASES", "EXPORTABLE", "SECTIONS", "MATCHES", "METHODS", "CONTROLLERS",
    "FMI_VERSIONS", "SIMULATORS", "TAPERED_SECTIONS", "quiet_unit_slips",
]

#: Plots a scene may ask for (``report.plots``): the slew responses, the open-loop transfer
#: L(j omega) (Bode and Nyquist), the closed-loop poles, W(s) of every appendage, the reference
#: profile (theta_ref, omega_ref, feedforward torque) and the reaction wheels' torque and
#: momentum against their limits.
PLOTS = ("slew", "loop", "poles", "W", "profile", "wheels")
#: Earlier names of plots, still accepted: ``bode`` (W(s) of the appendage), ``pole_zero``.
PLOT_ALIASES = {"bode": "W", "pole_zero": "poles"}
EXPORTABLE = ("plant", "controller", "closed_loop")
SECTIONS = ("rod", "tube", "rectangular", "uniform")
MATCHES = ("poles-and-zeros", "frequencies")
METHODS = ("craig-bampton", "residual", "free-free")
CONTROLLERS = ("pd", "lqr")
#: FMI versions of exported FMUs (``export.fmi_version``).
FMI_VERSIONS = ("2.0", "3.0")
#: Simulators of the manoeuvre (``simulator.name``): flexsat's own exact linear simulation, or
#: Basilisk beside it.
SIMULATORS = ("flexsat", "basilisk")


@contextlib.contextmanager
def quiet_unit_slips():
    """Build appendages and sensor noise from a read scene, and pass its loop delay to
    :mod:`controllers`, without the unit-slip warnings of the constructors and functions
    (:class:`appendages.unit_slips.UnitWarning`, :class:`controllers.LongDelayWarning`,
    :class:`controllers.LargeNoiseWarning`): the reader reported them by key."""
    from appendages.unit_slips import UnitWarning
    from controllers.delay import LongDelayWarning
    from controllers.noise import LargeNoiseWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnitWarning)
        warnings.simplefilter("ignore", LongDelayWarning)
        warnings.simplefilter("ignore", LargeNoiseWarning)
        yield


@dataclasses.dataclass(frozen=True)
class HubSpec:
    """Hub: mass [kg], inertia about its centre of mass [kg m^2]: a number (planar) or a 3x3
    tensor, rows as tuples (three axes)."""

    mass: float
    inertia: float | tuple

    @property
    def three_axis(self) -> bool:
        """True for a 3x3 inertia tensor."""
        return isinstance(self.inertia, tuple)


@dataclasses.dataclass(frozen=True)
class TipSpec:
    """A rigid body at a beam's free end (:class:`appendages.TipBody`): mass [kg]; inertia
    about its own centre of mass [kg m^2], a number (about z, planar) or a 3x3 tensor in the
    appendage's axes, rows as tuples (three axes); offset of its centre from the free end [m],
    a number along x or an ``(x, y, z)`` vector in the appendage's axes."""

    mass: float
    inertia: float | tuple
    offset: float | tuple = 0.0

    def build(self):
        """The :class:`appendages.TipBody`."""
        from appendages import TipBody

        inertia = self.inertia if not isinstance(self.inertia, tuple) else np.array(self.inertia)
        offset = self.offset if not isinstance(self.offset, tuple) else np.array(self.offset)
        return TipBody(self.mass, inertia, offset)


@dataclasses.dataclass(frozen=True)
class BeamSpec:
    """A uniform beam by section and material, optionally with a tip body (SI units; see the
    module table)."""

    section: str
    length: float
    dimensions: tuple          # (key, value) pairs: section dimensions [m], or EJ [N m^2] and
    #                            rho*A [kg/m] for "uniform"
    density: float | None      # kg/m^3
    youngs_modulus: float | None  # Pa
    damping_ratio: float
    poisson_ratio: float = 0.3  # - (shear modulus G = E / (2 (1 + nu)): torsion)
    tip: TipSpec | None = None
    kind: str = "beam"

    @property
    def uniform(self) -> bool:
        """True for a bare uniform beam (no tip body): the paper's closed forms apply (its
        two-mode free-free beam, its frequency fit, RFEM without a tip)."""
        return self.tip is None

    def build(self):
        """The :class:`appendages.Beam` (every property of a section filled: both bending
        planes, torsion and axial motion). The values that look like unit slips were reported
        by key when the scene was read: the constructors' own warnings are left out."""
        with quiet_unit_slips():
            return self._build(None if self.tip is None else self.tip.build())

    def _build(self, tip=None):
        from appendages import Beam

        d, z, nu = dict(self.dimensions), self.damping_ratio, self.poisson_ratio
        if self.section == "rod":
            return Beam.circular_rod(self.length, d["diameter"], self.density,
                                     self.youngs_modulus, poisson_ratio=nu, damping_ratio=z,
                                     tip=tip)
        if self.section == "tube":
            return Beam.tube(self.length, d["outer_diameter"], d["wall_thickness"], self.density,
                             self.youngs_modulus, poisson_ratio=nu, damping_ratio=z, tip=tip)
        if self.section == "rectangular":
            return Beam.rectangular(self.length, d["width"], d["thickness"], self.density,
                                    self.youngs_modulus, poisson_ratio=nu, damping_ratio=z,
                                    tip=tip)
        return Beam(self.length, d["bending_stiffness"], d["linear_density"], damping_ratio=z,
                    tip=tip)


@dataclasses.dataclass(frozen=True)
class SteppedBeamSpec:
    """Uniform segments end to end from the root (:class:`appendages.SteppedBeam`): each a
    :class:`BeamSpec` without tip body, all with the beam's damping ratio (of its cantilever
    modes); optionally a tip body at the free end."""

    segments: tuple
    damping_ratio: float
    tip: TipSpec | None = None
    kind: str = "stepped_beam"

    uniform = False

    @property
    def length(self) -> float:
        """Length of the beam [m]."""
        return math.fsum(segment.length for segment in self.segments)

    def build(self):
        """The :class:`appendages.SteppedBeam`; planar segments throughout when one of them is
        ``"uniform"`` (bending only: a planar scene's beam)."""
        from appendages import SteppedBeam

        with quiet_unit_slips():
            beams = [segment.build() for segment in self.segments]
            if any(segment.section == "uniform" for segment in self.segments):
                beams = [beam.planar_view("xy") for beam in beams]
            return SteppedBeam(beams, tip=None if self.tip is None else self.tip.build())


#: Section names of a scene and of :meth:`appendages.SteppedBeam.tapered`.
TAPERED_SECTIONS = {"rod": "circular_rod", "tube": "tube", "rectangular": "rectangular"}


@dataclasses.dataclass(frozen=True)
class TaperedBeamSpec:
    """A beam whose section dimensions vary linearly from root to free end, as
    ``n_segments`` uniform segments (:meth:`appendages.SteppedBeam.tapered`), optionally
    with a tip body (SI units)."""

    section: str
    length: float
    n_segments: int
    root_dimensions: tuple     # (key, value) pairs [m]
    tip_dimensions: tuple      # (key, value) pairs [m]
    density: float
    youngs_modulus: float
    damping_ratio: float
    poisson_ratio: float = 0.3
    tip: TipSpec | None = None
    kind: str = "tapered_beam"

    uniform = False

    def build(self):
        """The :class:`appendages.SteppedBeam` of ``n_segments`` segments."""
        from appendages import SteppedBeam

        with quiet_unit_slips():
            return SteppedBeam.tapered(
                self.length, self.n_segments, section=TAPERED_SECTIONS[self.section],
                root_dimensions=dict(self.root_dimensions),
                tip_dimensions=dict(self.tip_dimensions), density=self.density,
                youngs_modulus=self.youngs_modulus, poisson_ratio=self.poisson_ratio,
                damping_ratio=self.damping_ratio,
                tip=None if self.tip is None else self.tip.build())


#: Where modal data come from (``modal.file``, ``modal.nastran`` or the numbers in the scene).
MODAL_SOURCES = ("file", "nastran", "inline")


@dataclasses.dataclass(frozen=True)
class ModalSpec:
    """An appendage given by the cantilever modes of its finite-element model
    (:class:`appendages.ModalAppendage`), from a modal data file (TOML, units in the file), a
    NASTRAN normal-modes solution (an OP2 file read with pyNastran, or its ``.npz`` extract) or
    numbers in the scene (SI). Paths are absolute (resolved against the scene's folder).

    The facts after the fields (``n_modes``...) are the data's, filled when the scene is read,
    for the report; they take no part in comparing or hashing specs.
    """

    source: str
    path: str | None = None
    # NASTRAN: the root grid, the model's (length, mass) units, its mass matrix file, the grid
    # whose motion gives the tip motion, the appendage's axes in the basic system (rows), the
    # subcase
    root: int | None = None
    units: tuple | None = None
    mass_matrix: str | None = None
    tip_grid: int | None = None
    axes: tuple | None = None
    subcase: int | None = None
    # in the scene (SI): rad/s, sqrt(kg) and sqrt(kg) m, kg and kg m and kg m^2, m/sqrt(kg)...
    frequencies: tuple | None = None
    participation: tuple | None = None
    rigid_mass: tuple | None = None
    tip_motion: tuple | None = None
    # any source: the first n_modes modes only, the damping ratio(s) and the length [m] (None:
    # the data's)
    n_modes_kept: int | None = None
    damping: float | tuple | None = None
    length: float | None = None
    planar: bool = True
    kind: str = "modal"
    n_modes: int = dataclasses.field(default=0, compare=False)
    first_frequency: float = dataclasses.field(default=0.0, compare=False)
    last_frequency: float = dataclasses.field(default=0.0, compare=False)
    mass: float = dataclasses.field(default=0.0, compare=False)
    has_tip_motion: bool = dataclasses.field(default=False, compare=False)
    damping_range: tuple = dataclasses.field(default=(0.0, 0.0), compare=False)

    uniform = False

    @property
    def damping_ratio(self) -> float:
        """The largest damping ratio of the modes [-] (the data's, or the scene's)."""
        return self.damping_range[1]

    def build(self):
        """The :class:`appendages.ModalAppendage`: its x-y plane in a planar scene (held root
        motions out of the plane), all six root motions in a three-axis one. Read once per
        file version and options (memoised in the process)."""
        stamps = tuple(_file_stamp(p) for p in (self.path, self.mass_matrix) if p is not None)
        return _modal_appendage(self, stamps)


def _file_stamp(path: str) -> tuple:
    """(modification time [ns], size [bytes]) of a file: a changed file is read again."""
    import os

    try:
        info = os.stat(path)
    except OSError:
        return (None, None)
    return (info.st_mtime_ns, info.st_size)


def load_mass_matrix(path: str):
    """A finite-element mass matrix from a NumPy file: ``.npy`` (a dense square array) or
    ``.npz`` (a scipy.sparse matrix saved with :func:`scipy.sparse.save_npz`).

    Raises
    ------
    ValueError
        Another suffix, or a file that is not such an array.
    OSError
        The file cannot be read.
    """
    import scipy.sparse

    if path.lower().endswith(".npy"):
        try:
            return np.load(path, allow_pickle=False)
        except ValueError as exc:
            raise ValueError(f"mass_matrix {path}: not a NumPy array file ({exc})") from None
    if path.lower().endswith(".npz"):
        try:
            return scipy.sparse.load_npz(path)
        except (ValueError, KeyError) as exc:
            raise ValueError(f"mass_matrix {path}: not a scipy.sparse .npz file ({exc})") \
                from None
    raise ValueError(f"mass_matrix must be a .npy file (a dense array) or a .npz file "
                     f"(scipy.sparse.save_npz); got {path}")


@functools.lru_cache(maxsize=16)
def _modal_appendage(spec: ModalSpec, stamps: tuple):
    """:meth:`ModalSpec.build`, memoised on the spec and its files' stamps."""
    from appendages import ModalAppendage, read_modal_data, read_nastran

    with quiet_unit_slips():
        if spec.source == "file":
            model = read_modal_data(spec.path)
            if spec.damping is not None or spec.length is not None:
                damping = model.damping_ratios if spec.damping is None else spec.damping
                model = ModalAppendage(model.frequencies, model.participation,
                                       model.rigid_mass, damping=damping,
                                       length=spec.length if spec.length is not None else
                                       _length_or_none(model), tip_motion=model.tip_motion)
        elif spec.source == "nastran":
            options = {"axes": None if spec.axes is None else np.array(spec.axes),
                       "damping": 0.0 if spec.damping is None else spec.damping,
                       "length": spec.length, "tip": spec.tip_grid}
            if spec.mass_matrix is not None:
                options["mass_matrix"] = load_mass_matrix(spec.mass_matrix)
            model = read_nastran(spec.path, root=spec.root, units=spec.units,
                                 subcase=spec.subcase, **options)
        else:
            model = ModalAppendage(
                np.array(spec.frequencies), np.array(spec.participation),
                np.array(spec.rigid_mass), damping=0.0 if spec.damping is None else
                (np.array(spec.damping) if isinstance(spec.damping, tuple) else spec.damping),
                length=spec.length,
                tip_motion=None if spec.tip_motion is None else np.array(spec.tip_motion))
        if spec.n_modes_kept is not None:
            model = model.truncated(spec.n_modes_kept)
        if spec.planar and model.three_axis:
            model = model.planar_view("xy")
    return model


def _length_or_none(model):
    """A modal appendage's length [m], or None when its data give none."""
    try:
        return model.length
    except ValueError:
        return None


@dataclasses.dataclass(frozen=True)
class ChainSpec:
    """A hinged chain: explicit arrays, or rigid finite elements of the appendage's beam.

    The arrays are :class:`appendages.HingedChain`'s: ``inertias``, ``hinge_stiffnesses`` and
    ``hinge_dampings`` of x-y bending; in a three-axis scene also those of x-z bending
    (``..._y``; None: the x-y ones), the torsion (``torsional_inertias``, required there;
    ``torsion_stiffnesses`` None: torsionally rigid joints) and the axial springs (None:
    inextensible)."""

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
    # three axes (an explicit chain): x-z bending (None: as x-y), torsion, axial motion
    inertias_y: tuple | None = None
    hinge_stiffnesses_y: tuple | None = None
    hinge_dampings_y: tuple | None = None
    torsional_inertias: tuple | None = None
    torsion_stiffnesses: tuple | None = None
    torsion_dampings: tuple | None = None
    axial_stiffnesses: tuple | None = None
    axial_dampings: tuple | None = None


@dataclasses.dataclass(frozen=True)
class FitSpec:
    """Chain fit: number of bodies and one or more matching criteria."""

    n_bodies: int = 3
    match: tuple = MATCHES


@dataclasses.dataclass(frozen=True)
class AppendageSpec:
    """One mounted appendage: name, mount (position [m], direction [rad]) and its models: its
    structure (``beam``: a :class:`BeamSpec`, :class:`SteppedBeamSpec` or
    :class:`TaperedBeamSpec`; or ``modal``: a :class:`ModalSpec`), its chains, the fit. Its
    ``truth`` is ``"beam"``, ``"modal"`` or ``"chain"``."""

    name: str
    position: tuple
    direction: float
    truth: str
    design: str
    beam: BeamSpec | None
    chain: ChainSpec | None
    fit: FitSpec | None
    truth_chain: ChainSpec | None = None
    orientation: tuple | None = None  # three axes: 3x3 rotation, rows (columns: local x, y, z)
    modal: ModalSpec | None = None

    @property
    def structure(self):
        """The spec of the appendage's structure (its exact model): a beam (uniform, stepped,
        tapered) or modal data; None for a chain alone."""
        return self.beam if self.beam is not None else self.modal


@dataclasses.dataclass(frozen=True)
class FidelitySpec:
    """Truth-model fidelity: a fixed n_modes, or a tolerance from which n_modes is chosen.

    ``modes_per_motion`` (with ``n_modes`` only; None when not given): per truncated-beam
    appendage, the modes pinned per motion, ``((appendage, ((motion, count), ...)), ...)``:
    what a run from ``tolerance`` adds for its tip outputs (:meth:`pinned_floors`). Given (even
    empty), a three-axis truncation keeps the lowest mode of both bending planes and torsion
    (and axial with root loads), as a run from ``tolerance`` with tip outputs does, whatever
    the scene's outputs.
    """

    n_modes: int | None = None
    tolerance: float | None = 1e-3
    method: str = "craig-bampton"
    bandwidth_factor: float = 5.0
    prune: bool = True
    modes_per_motion: tuple | None = None

    def pinned_floors(self) -> dict:
        """``modes_per_motion`` as ``{appendage: {motion: count}}`` (empty when not given)."""
        return {name: dict(counts) for name, counts in self.modes_per_motion or ()}


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
    """Controllers to tune on the design model and their sample time [s] (None: continuous);
    ``given``: one of them given as numbers instead of tuned (:mod:`spacecraft.scene.given`)."""

    types: tuple
    pd: PDSpec | None
    lqr: LQRSpec | None
    sample_time: float | None = None
    given: object = None
    delay: float = 0.0             # s: loop delay (computation plus transport)
    computation_delay: bool = False  # a digital controller's one sample added to the delay

    @property
    def total_delay(self) -> float:
        """The loop's delay [s]: ``delay`` plus one sample with ``computation_delay``."""
        return self.delay + (self.sample_time if self.computation_delay else 0.0)


@dataclasses.dataclass(frozen=True)
class DisturbanceSpec:
    """A rectangular pulse on a plant disturbance input (N or N m), from start [s] for length [s];
    three axes: ``"disturbance_torque"`` or ``"force"`` along ``axis`` (unit vector, hub
    axes)."""

    input: str
    amplitude: float
    start: float = 0.0
    length: float | None = None
    axis: tuple | None = None


@dataclasses.dataclass(frozen=True)
class ShaperSpec:
    """Input shaper of a ``"shaped"`` profile: ``kind`` ("zv", "zvd") on the ``modes`` lowest
    flexible modes of each design model, convolved with a ``base`` profile
    ("bang-coast-bang", "smooth"); the residual vibration stays at or below ``tolerance`` (a
    fraction of the unshaped one) for a frequency error of +-``frequency_error`` (a fraction;
    None: not asked)."""

    kind: str = "zvd"
    modes: int = 1
    base: str = "bang-coast-bang"
    frequency_error: float | None = None
    tolerance: float = 0.05


@dataclasses.dataclass(frozen=True)
class ManoeuvreSpec:
    """Slew of slew_angle [rad] in slew_time [s], simulated for duration [s] at step [s].

    ``profile`` is the reference (:data:`controllers.PROFILE_KINDS`): ``"step"``, the cycloid
    of theta_ref alone, or a rest-to-rest profile under ``torque_limit`` [N m], ``rate_limit``
    [rad/s] and ``jerk_limit`` [rad/s^3] ending at slew_time; ``feedforward`` feeds its rate
    reference and feedforward torque to controllers tuned to take them."""

    slew_angle: float
    slew_time: float
    duration: float
    step: float
    disturbance: DisturbanceSpec | None = None
    slew_axis: tuple | None = None  # three axes: unit vector of the eigen-axis slew, hub axes
    profile: str = "step"
    feedforward: bool = False
    torque_limit: float | None = None   # N m
    rate_limit: float | None = None     # rad/s
    jerk_limit: float | None = None     # rad/s^3
    shaper: ShaperSpec | None = None

    @property
    def flown(self) -> bool:
        """True for anything but today's reference: a profile other than the step, or
        feedforward."""
        return self.profile != "step" or self.feedforward


@dataclasses.dataclass(frozen=True)
class OutputsSpec:
    """Which outputs to build: tip deflections, root loads, exact-beam references."""

    tip_deflection: bool = False
    root_loads: bool = False
    exact_reference: bool = False


@dataclasses.dataclass(frozen=True)
class ExportSpec:
    """FMU export: whether, which systems, cross-check files, communication step [s], FMI
    versions, sources-only FMUs, SSP files of plant and controller."""

    fmu: bool = False
    systems: tuple = EXPORTABLE
    reference_files: bool = True
    step: float | None = None
    fmi_versions: tuple = ("2.0",)
    sources_only: bool = False
    ssp: bool = False


@dataclasses.dataclass(frozen=True)
class ReportSpec:
    """Plots wanted, whether to tabulate the equivalence criterion, whether to write the time
    series (CSV files beside results.json)."""

    plots: tuple = ()
    equivalence: bool = True
    timeseries: bool = True


@dataclasses.dataclass(frozen=True)
class ReactionWheelSpec:
    """A reaction wheel about the hub's z axis for the Basilisk run (kg m^2, N m, rad/s)."""

    spin_inertia: float
    max_torque: float | None = None
    max_speed: float | None = None


@dataclasses.dataclass(frozen=True)
class WheelsSpec:
    """Reaction wheels between the controller's torque command and the hub
    (:class:`controllers.WheelSet`): per wheel (a number for every wheel, or one per wheel)
    torque limit [N m], momentum limit [N m s], spin inertia [kg m^2] (None: not given),
    viscous [N m s/rad] and Coulomb [N m] friction; three axes: the wheels' unit spin axes
    (hub axes, rows) or a 4-wheel pyramid about +z ``(cant_angle, azimuth)`` [rad], and the
    torque saturation rule."""

    torque_limit: float | tuple
    momentum_limit: float | tuple
    spin_inertia: float | tuple | None = None
    viscous_friction: float | tuple = 0.0
    coulomb_friction: float | tuple = 0.0
    spin_axes: tuple | None = None
    pyramid: tuple | None = None
    saturation: str = "scale"

    @property
    def n_wheels(self) -> int:
        """1 (planar), the rows of ``spin_axes``, or 4 (pyramid)."""
        if self.spin_axes is not None:
            return len(self.spin_axes)
        return 4 if self.pyramid is not None else 1

    def value(self, name: str, k: int):
        """Wheel ``k``'s value of a per-wheel field."""
        v = getattr(self, name)
        return v[k] if isinstance(v, tuple) else v

    def build(self):
        """The :class:`controllers.WheelSet`."""
        import controllers

        wheels = [controllers.ReactionWheel(
            torque_limit=self.value("torque_limit", k),
            momentum_limit=self.value("momentum_limit", k),
            spin_inertia=self.value("spin_inertia", k),
            viscous_friction=self.value("viscous_friction", k),
            coulomb_friction=self.value("coulomb_friction", k)) for k in range(self.n_wheels)]
        if self.pyramid is not None:
            if len(set(wheels)) == 1:
                return controllers.WheelSet.pyramid(wheels[0], self.pyramid[0],
                                                    azimuth=self.pyramid[1],
                                                    saturation=self.saturation)
            import numpy as np

            beta, a0 = self.pyramid
            a = a0 + 0.5 * math.pi * np.arange(4)
            axes = np.column_stack([math.sin(beta) * np.cos(a), math.sin(beta) * np.sin(a),
                                    np.full(4, math.cos(beta))])
            return controllers.WheelSet(wheels, axes, saturation=self.saturation)
        return controllers.WheelSet(wheels if self.spin_axes is not None else wheels[0],
                                    self.spin_axes, saturation=self.saturation)


@dataclasses.dataclass(frozen=True)
class SensorsSpec:
    """Sensor noise (:class:`controllers.SensorNoise`; a number for every axis or three):
    attitude sensor white-noise density [rad/sqrt(Hz)], gyro angle random walk [rad/sqrt(s)],
    bias instability [rad/s] and its correlation time [s]; the pointing figures' RPE window
    [s], where t lies in it (``"random"``, ``"end"``) and the probability level they are also
    given at."""

    attitude_density: float | tuple = 0.0
    angle_random_walk: float | tuple = 0.0
    bias_instability: float | tuple = 0.0
    bias_correlation_time: float | tuple | None = None
    rpe_window: float = 1.0
    placement: str = "random"
    probability: float = 0.9973

    def noise(self):
        """The :class:`controllers.SensorNoise` (a level that looks like a unit slip was
        reported by key when the scene was read)."""
        import controllers

        with quiet_unit_slips():
            return controllers.SensorNoise(
                attitude_density=self.attitude_density,
                angle_random_walk=self.angle_random_walk,
                bias_instability=self.bias_instability,
                bias_correlation_time=self.bias_correlation_time)


@dataclasses.dataclass(frozen=True)
class SimulatorSpec:
    """Who simulates the manoeuvre besides flexsat: ``"flexsat"`` (nobody else) or
    ``"basilisk"`` (the design chains in Basilisk, flight-software sample time [s], RK4 step
    [s], optional reaction wheel)."""

    name: str = "flexsat"
    sample_time: float | None = None
    dt: float | None = None
    reaction_wheel: ReactionWheelSpec | None = None


@dataclasses.dataclass(frozen=True)
class Scene:
    """A validated scene (SI units). Build it with :func:`~spacecraft.scene.read.load_scene` or
    :func:`~spacecraft.scene.read.default_scene`."""

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
    limits: Limits = Limits()
    simulator: SimulatorSpec = SimulatorSpec()
    #: Values that look like unit slips, one line each naming the key and the likely mistake
    #: (:mod:`appendages.unit_slips`); the run reports them with its warnings.
    input_warnings: tuple = ()
    wheels: WheelsSpec | None = None
    sensors: SensorsSpec | None = None

    @property
    def three_axis(self) -> bool:
        """True if the hub has a 3x3 inertia tensor (a three-axis scene)."""
        return self.hub.three_axis

    def replace(self, **changes) -> "Scene":
        """A copy with some top-level parts replaced (e.g. ``export=ExportSpec(fmu=False)``)."""
        return dataclasses.replace(self, **changes)

    @property
    def has_beam_truth(self) -> bool:
        """True if some appendage's truth model is a distributed beam."""
        return any(a.truth == "beam" for a in self.appendages)

    @property
    def has_exact_truth(self) -> bool:
        """True if some appendage's truth model has an exact W: a distributed beam, or modal
        data (exact for the modes they hold)."""
        return any(a.truth in ("beam", "modal") for a in self.appendages)

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


def _plain(value):
    """Dataclasses, tuples and numbers as JSON-ready Python (tuples of pairs of a section's
    dimensions become a table)."""
    if dataclasses.is_dataclass(value):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple) and value and all(
            isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], str) for v in value):
        return {k: _plain(v) for k, v in value}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def scene_dict(scene: Scene) -> dict:
    """The resolved scene: every key with its value after defaults, SI units inside (angles in
    rad, ``sample_time`` [s] for the file's ``sample_rate`` [Hz]), JSON-ready.

    Returns
    -------
    dict
        Mirrors :class:`Scene` (``appendages`` a list of tables; a beam's section dimensions a
        table ``dimensions``), plus ``units`` naming the unit system.
    """
    out = _plain(scene)
    del out["input_warnings"]  # reported with the run's warnings, not a key of the scene
    out["units"] = ("SI: m, kg, s, N, Pa, rad (slew_angle, direction), rad/s; controller and "
                    "simulator sample_time in s")
    return out
