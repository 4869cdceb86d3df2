"""Work limits of a scene: its cost is estimated before anything is built, and refused by name.

A scene can ask for minutes of computing and gigabytes of memory with one number
(``fidelity.n_modes = 5000``, ``manoeuvre.step = 1e-6``). :func:`estimate_cost` bounds, from the
validated scene alone, the sizes that drive the cost of a run: states of the largest plant and
closed loop, samples per simulation, number of simulations and the memory their responses
take. The scene reader (:mod:`spacecraft.scene.read`) compares them and the scene's counts (modes,
bodies, appendages, string lengths) with :class:`Limits` and refuses, naming the scene key and
the limit, whatever exceeds one. A user who really wants more raises the limit explicitly: a
``[limits]`` table in the scene or ``--limit NAME=VALUE`` on the command line.

Defaults (the table of ``spacecraft/scene/read.py`` and the README), measured on the development
machine (2 cores, load average 2-3; medians of single runs, noisy):

================= ============ ============================================================
limit             default      what it bounds, and the cost at the limit
================= ============ ============================================================
modes             500          ``fidelity.n_modes`` (bending modes per truncated beam); the
                               search from ``fidelity.tolerance`` tries at most 40 (fewer if
                               this limit is lower; ``spacecraft.design.fidelity.MAX_MODES`` says why)
bodies            500          bodies of an explicit or ``from_beam`` chain (a 500-body
                               truth chain has 998 states)
fit_bodies        14           ``fit.n_bodies``: appendages' own limit (``appendages.limits``),
                               the range the "poles-and-zeros" fit is benchmarked and tested on
                               (its cost per body: benchmarks/results/fit.md); raising it raises
                               appendages' too
appendages        64           mounted appendages
states            1200         states of the largest closed loop (upper bound: truth plant
                               plus controller): tens of seconds and about 2 GB at the limit;
                               counted again on the models the run builds, before any
                               controller is tuned (a three-axis beam with a tip body or
                               segments keeps the modes its tip motions need, which only its
                               modes tell: ``ModelBuilder.check_loop_states``)
samples           10,000,000   samples of one simulation (duration / step + 1); a sample
                               of a digital loop counts 20 (scipy's dlsim steps in
                               Python, some 30 times the continuous simulator's cost per
                               sample), so 500,000 there
memory            2 GiB        bytes held by the time responses (upper bound: every response
                               kept, plus one simulation's work arrays)
string_length     4096         characters of a free-text value (``title``)
file_size         1 MiB        bytes of a scene file (``--limit file_size=...`` only: the
                               file's own [limits] table is read after the file)
basilisk_seconds  600 s        estimated wall time of one Basilisk run (``simulator.name =
                               "basilisk"``; the work model of
                               ``spacecraft.basilisk.simulation.STEP_SECONDS``: RK4 steps times
                               the chain's bodies cubed): a 30-body chain at its default step
                               takes minutes, a 40-body chain hours
================= ============ ============================================================
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

__all__ = ["Limits", "LIMIT_UNITS", "REAL_LIMITS", "SceneCost", "estimate_cost", "appendage_dof",
           "controller_states", "delay_states", "DIGITAL_SAMPLE_COST", "library_limits"]

#: Unit and meaning of each limit (for messages and ``--help``).
LIMIT_UNITS = {
    "modes": ("-", "bending modes per truncated beam"),
    "bodies": ("-", "bodies per chain"),
    "fit_bodies": ("-", "bodies of a fitted chain"),
    "appendages": ("-", "appendages per scene"),
    "states": ("-", "states of the largest closed loop"),
    "samples": ("-", "samples per simulation"),
    "memory": ("bytes", "memory of the time responses"),
    "string_length": ("characters", "length of a free-text value"),
    "file_size": ("bytes", "size of a scene file"),
    "basilisk_seconds": ("s", "estimated wall time of a Basilisk run"),
}
#: Limits that are real numbers; the others are whole numbers.
REAL_LIMITS = ("memory", "basilisk_seconds")

# Bytes per float64.
_FLOAT = 8

# the fit's limit is appendages.limits.DEFAULTS["fit_bodies"] (one number for the scene, the
# command line and the library; a test checks they agree; not imported: appendages loads scipy)
_LIBRARY_FIT_BODIES = 14

#: Continuous-loop samples one sample of a digital (sampled-data) loop costs as much as.
DIGITAL_SAMPLE_COST = 20


@dataclasses.dataclass(frozen=True)
class Limits:
    """Documented bounds on the work of one scene run (see the module table).

    Every field is a finite number >= 1 (:data:`LIMIT_UNITS` gives the units), a whole number
    except those of :data:`REAL_LIMITS`; ``memory`` and ``file_size`` are in bytes,
    ``basilisk_seconds`` in seconds.

    Raises
    ------
    TypeError
        A field that is not a real number (None, a string, a bool).
    ValueError
        A field that is not finite, below 1, or not whole where it must be.
    """

    modes: int = 500
    bodies: int = 500
    fit_bodies: int = _LIBRARY_FIT_BODIES
    appendages: int = 64
    states: int = 1200
    samples: int = 10_000_000
    memory: float = 2.0 * 1024**3
    string_length: int = 4096
    file_size: int = 1024**2
    basilisk_seconds: float = 600.0

    def __post_init__(self):
        for field in dataclasses.fields(self):
            object.__setattr__(self, field.name, _limit(field.name, getattr(self, field.name)))

    def replace(self, **changes) -> "Limits":
        """A copy with some limits changed."""
        return dataclasses.replace(self, **changes)

    @staticmethod
    def names() -> tuple:
        """Names of the limits (the keys of a scene's ``[limits]`` table)."""
        return tuple(f.name for f in dataclasses.fields(Limits))


def _limit(name: str, value):
    """A limit's value checked (:class:`Limits`): int, or float for :data:`REAL_LIMITS`."""
    import math
    import numbers

    unit = LIMIT_UNITS[name][0]
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"limit {name} must be a number >= 1 [{unit}]; got "
                        f"{type(value).__name__} {value!r}"[:200])
    try:
        number = float(value)
    except OverflowError:  # an int beyond the float range
        number = math.inf
    if not (math.isfinite(number) and number >= 1):
        raise ValueError(f"limit {name} must be a finite number >= 1 [{unit}]; got {value!r}"
                         [:200])
    if name in REAL_LIMITS:
        return number
    if number != math.floor(number):
        raise ValueError(f"limit {name} must be a whole number [{unit}]; got {value!r}")
    return int(number)


@dataclasses.dataclass(frozen=True)
class SceneCost:
    """Upper bounds of the sizes that drive the cost of running a scene.

    Attributes
    ----------
    samples : int
        Samples per simulation (0 without a manoeuvre).
    simulations : int
        Time responses computed (design and truth loop per design variant and controller).
    plant_states : int
        States of the largest plant (truth or design), before pruning.
    loop_states : int
        States of the largest closed loop (plant plus controller).
    loop_key : str
        The scene key that contributes most to ``loop_states`` (named in a refusal).
    memory : float, bytes
        Memory held by the time responses, plus one simulation's work arrays.
    """

    samples: int
    simulations: int
    plant_states: int
    loop_states: int
    loop_key: str
    memory: float

    def as_dict(self) -> dict:
        """JSON-ready copy."""
        return dataclasses.asdict(self)


def _chain_bodies(chain) -> int:
    return chain.n_bodies if chain.from_beam is not None else len(chain.lengths)


def appendage_dof(spec, which: str, n_modes: int | None, floor: int = 0, *,
                  three_axis: bool = False) -> tuple[int, str]:
    """Elastic degrees of freedom of an appendage's truth or design model, and the key behind.

    Parameters
    ----------
    spec : spacecraft.scene.read.AppendageSpec
    which : {"truth", "design"}
    n_modes : int or None
        Bending modes of a truncated beam (None: the smallest, 1, as a tolerance search starts).
    floor : int
        Modes a truncated beam keeps beyond ``n_modes`` (a three-axis truncation's lowest mode
        of every motion a reported output sees).
    three_axis : bool
        A three-axis spacecraft: each hinge of a chain moves in four ways (bending in both
        planes, torsion, axial: :class:`appendages.HingedChain`'s three-axis root model).

    Returns
    -------
    (int, str)
        Degrees of freedom (bending modes, or hinge motions of a chain) and the key path that
        sets them
        (relative to the appendage: ``"fit.n_bodies"``, ``"chain"``...; ``"fidelity.n_modes"``
        is absolute).
    """
    kind = spec.truth if which == "truth" else spec.design
    if which == "design" and kind == "truth":
        return appendage_dof(spec, "truth", n_modes, floor, three_axis=three_axis)
    motions = 4 if three_axis else 1
    if kind == "beam":
        return (1 if n_modes is None else n_modes) + floor, "fidelity.n_modes"
    if kind == "modal":
        return spec.modal.n_modes, "modal"
    if kind == "fit":
        return motions * (spec.fit.n_bodies - 1), "fit.n_bodies"
    chain, key = ((spec.truth_chain, "truth_chain") if which == "truth" and spec.truth_chain
                  else (spec.chain, "chain"))
    n = _chain_bodies(chain)
    return motions * (n if chain.root == "hinged" else n - 1), key


def controller_states(controller, kind: str, design_states: int, three_axis: bool) -> int:
    """States of a scene's controller of type ``kind``, known before it is tuned.

    Parameters
    ----------
    controller : spacecraft.scene.specs.ControllerSpec
        The scene's ``[controller]`` table.
    kind : {"pd", "lqr"}
    design_states : int
        States of the design plant the controller is tuned on.
    three_axis : bool
        A three-axis spacecraft (three torques).

    Returns
    -------
    int
        A given controller's (``controller.given`` of this type): its states. A PD's: each
        filter, roll-off and notch, is second order per torque (:func:`controllers.pd`; the
        PD itself is static). An LQR's: its Kalman estimator has the design plant's states (at
        most: modes the loop cannot influence are left out, :func:`controllers.lqr`).
    """
    given = controller.given
    if given is not None and given.kind == kind:
        return int(given.n_states)
    if kind == "pd":
        pd = controller.pd
        return (3 if three_axis else 1) * (2 * (pd.roll_off is not None)
                                           + 2 * (pd.notch is not None))
    return int(design_states)


def delay_states(scene) -> int:
    """States of the delay line of a scene's delayed loop (0 without a delay).

    A loop with ``controller.delay`` (or ``computation_delay``) is discrete on a step T: the
    digital controller's sample time, else the manoeuvre's step (without one, twice the delay),
    the command held over each step (:func:`spacecraft.design.manoeuvre.close_flown_loop`). Its
    states end with the past commands the delay reaches back to, per torque k + 1 for a shift
    (k + f) T with 0 < f < 1, k for f = 0 (:func:`controllers.delay.delayed_closed_loop`, f
    as :func:`controllers.delay.split_delay` snaps it), the shift the whole delay for a
    digital controller, the delay less the hold's mean delay T / 2 for a continuous one.
    """
    import warnings

    from controllers.delay import LongDelayWarning, split_delay

    c = scene.controller
    tau = c.total_delay
    if not tau > 0:
        return 0
    if c.sample_time is not None:
        step, shift = c.sample_time, tau
    else:
        m = scene.manoeuvre
        step = m.step if m is not None else 2.0 * c.delay
        shift = max(tau - 0.5 * step, 0.0)
    if not shift > 0:
        return 0
    with warnings.catch_warnings():
        # a long delay is the reader's to report, by key
        warnings.simplefilter("ignore", LongDelayWarning)
        k, f = split_delay(shift, step)
    return (3 if scene.three_axis else 1) * (k + (f > 0))


def _controller_states(scene, design_states: int) -> int:
    """Upper bound of the controller's states at read time: two more than
    :func:`controller_states` counts for the largest of the scene's controllers (a margin the
    read-time bound has always kept; the run checks the loops it builds exactly,
    :meth:`spacecraft.design.models.ModelBuilder.check_loop_states`)."""
    return max((2 + controller_states(scene.controller, kind, design_states, scene.three_axis)
                for kind in scene.controller.types), default=0)


def estimate_cost(scene, *, kept: Mapping[str, int] | None = None) -> SceneCost:
    """Upper bounds of a scene's plant and loop sizes, samples and response memory.

    Parameters
    ----------
    scene : spacecraft.scene.read.Scene
        A validated scene (its limits are not consulted here).
    kept : mapping of str to int, optional
        Modes a truncated truth beam keeps beyond ``fidelity.n_modes``, by appendage name,
        where the caller knows them from the beam's modes (the run: a three-axis beam whose
        modes are ranked together keeps its k0 - 1 lowest beyond n, k0 the fewest that move
        every tip motion, :meth:`spacecraft.design.models.ModelBuilder.coupled_floor`);
        counted instead of the read-time rule's floor (a uniform round beam's twins are still
        added).

    Returns
    -------
    SceneCost

    Notes
    -----
    A plant of N elastic degrees of freedom on the hub has at most 2 (3 + N) states (hub
    translation and rotation plus the appendages' modes or hinges; pruning only removes); a
    three-axis one 2 (3 + N) under torques (the hub's rotations), 2 (6 + N) with its
    translations, with disturbance inputs. A three-axis chain's hinge
    moves in four ways (bending in both planes, torsion, axial).
    The loop adds the controller (:func:`controller_states`, and two states of margin) and a
    delayed loop's delay line (:func:`delay_states`).
    A three-axis beam whose modes are ranked together (a tip body, segments) keeps, when a
    reported output or a pin asks for a mode of every tip motion, the fewest lowest modes k0
    that move them all and n - 1 more: k0 follows from its modes, which this estimate does not
    compute (it counts n and a mode per motion); the run counts the loops it builds and
    refuses one over limits.states before tuning
    (:meth:`spacecraft.design.models.ModelBuilder.check_loop_states`).
    A uniform three-axis beam of round section (rod, tube, square) counts its bending twins:
    beyond a floor each of the n counts a distinct frequency, at most a pair, and without one
    the n lowest may end on a twin.
    A truth beam chosen from ``fidelity.tolerance`` is counted with one mode: the search stops
    at the smallest sufficient number, and the runner caps it by the limits; in three axes with
    reported tip outputs or root loads, also with the lowest mode of every motion they see
    (both bending planes and torsion, and the axial motion with root loads), which such a
    truncation keeps whatever n (:meth:`spacecraft.design.models.ModelBuilder.truncation`),
    and with the modes ``fidelity.modes_per_motion`` pins.
    Memory: a response keeps time, inputs and outputs (8 bytes per sample each); one simulation
    needs in addition its chunked work arrays, at most about (states + 4 inputs + 2 outputs)
    values per sample.
    """
    apps = scene.appendages
    fidelity = scene.fidelity
    n_modes = fidelity.n_modes
    outputs = scene.outputs
    # the modes per motion a three-axis truncation chosen from the tolerance (or given with
    # modes pinned per motion) keeps beyond n
    pinned_truth = n_modes is not None and fidelity.modes_per_motion is not None
    seen = (("xy", "xz", "torsion") + (("axial",) if outputs.root_loads else ())
            if scene.three_axis and (pinned_truth or (
                n_modes is None and (outputs.tip_deflection or outputs.root_loads))) else ())
    pinned = fidelity.pinned_floors()

    def floor(a) -> int:
        if kept is not None and a.name in kept:
            return int(kept[a.name]) + twins(a)
        mine = pinned.get(a.name, {})
        return (len(seen) + sum(max(0, k - (m in seen)) for m, k in mine.items())
                + twins(a))

    def twins(a) -> int:
        # a uniform round section's bending modes come in x-y / x-z pairs: beyond a floor
        # each of the n counts a distinct frequency, a pair at most (n more); without one the
        # n lowest and a twin tying with the last (one more)
        beam = a.beam
        if not (scene.three_axis and a.truth == "beam" and getattr(beam, "uniform", False)):
            return 0
        d = dict(beam.dimensions)
        round_ = beam.section in ("rod", "tube") or (
            beam.section == "rectangular" and d.get("width") == d.get("thickness"))
        if not round_:
            return 0
        return (1 if n_modes is None else n_modes) if (seen or pinned.get(a.name)) else 1

    three = scene.three_axis
    truth = [appendage_dof(a, "truth", n_modes, floor(a), three_axis=three) for a in apps]
    design = [appendage_dof(a, "design", n_modes, floor(a), three_axis=three) for a in apps]
    # every design variant (one per fit criterion) has fits of the same size
    m = scene.manoeuvre
    # the hub's rotations (and the planar hub's translations); a three-axis plant with
    # disturbance inputs has its three translations too (pruning may keep them)
    rigid = 6 if (three and m is not None and m.disturbance is not None) else 3
    truth_states = 2 * (rigid + sum(d for d, _ in truth))
    design_states = 2 * (rigid + sum(d for d, _ in design))
    plant_states = max(truth_states, design_states)
    loop_states = plant_states + _controller_states(scene, design_states) + delay_states(scene)
    # the key behind the largest contribution
    contributions = [(d, key if key == "fidelity.n_modes" else f"appendages[{k}].{key}")
                     for dofs in (truth, design) for k, (d, key) in enumerate(dofs)]
    # (a degree of freedom is two states)
    contributions.append((delay_states(scene) / 2, "controller.delay"))
    loop_key = max(contributions)[1]

    m = scene.manoeuvre
    if m is None:
        return SceneCost(0, 0, plant_states, loop_states, loop_key, 0.0)
    samples = int(m.duration / m.step + 1e-9) + 1
    simulations = 2 * len(scene.design_variants) * len(scene.controller.types)
    n_app = len(apps)
    inputs = 1 + ((3 + n_app) if m.disturbance is not None else 0)
    outputs = (3 + n_app * scene.outputs.tip_deflection + 2 * n_app * scene.outputs.root_loads)
    kept = simulations * (1 + inputs + outputs)
    work = loop_states + 4 * inputs + 2 * outputs
    memory = float(_FLOAT) * samples * (kept + work)
    return SceneCost(samples, simulations, plant_states, loop_states, loop_key, memory)


def library_limits(limits: Limits):
    """A context in which :mod:`appendages.limits` allows what ``limits`` allows: a scene or
    ``--limit`` that raises ``modes``, ``bodies`` or ``fit_bodies`` above appendages' own
    defaults raises those too (never lowers them: the scene's check came first)."""
    from appendages import limits as library

    raised = {name: getattr(limits, name) for name in ("modes", "bodies", "fit_bodies")
              if getattr(limits, name) > library.current(name)}
    return library.raised(**raised)
