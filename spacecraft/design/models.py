"""The models a scene needs, built once: appendages, spacecraft, plants, exact references.

:class:`ModelBuilder` builds, for one scene, the distributed beams, the chains (explicit, RFEM
or fitted to a beam), the truncated truth models, the coupled :class:`Spacecraft` of each model
set, the state-space plants with the signals asked for, and the exact frequency-domain
references through W(s) of the distributed beams; it chooses the number of modes from the
scene's tolerance (:mod:`spacecraft.design.fidelity`). Everything is cached for the run: one chain fit
per (beam, criterion), one Spacecraft (one eigen-decomposition) per model set, one plant per
signal set. An error of flexsat's API raised by a call made with the scene's values becomes a
:class:`SceneError` naming the scene key (:meth:`ModelBuilder.scene_values`).

The scene runner (:mod:`spacecraft.design.loop`) and the sweeps (:mod:`spacecraft.sweep`) build on it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

import appendages
import controllers
from appendages.interface import FlexsatError

from ..dynamics.coupling import Spacecraft
from .fidelity import (MAX_MODES, OUTPUT_MOTIONS, FidelityChoice, choose_n_modes,
                       clamped_frequencies, motion_counts, output_changes,
                       refine_for_closed_loop, refine_for_tip_outputs)
from ..dynamics.hub import Hub, Mount
from ..scene.limits import appendage_dof, controller_states, delay_states, estimate_cost
from ..scene.read import AppendageSpec, ChainSpec, Scene, SceneError
from ..scene.specs import quiet_unit_slips
from .exact_grid import (POINTS_PER_DECADE, POINTS_PER_MODE, exact_grid, locating_spacecraft,
                         locator_model)
from .manoeuvre import loop_delay
from .verdicts import closed_loop_poles, crossover_frequencies, exact_loop_verdict

__all__ = ["ModelBuilder", "GivenModels", "TruthLoop", "RunStats", "raised_by_flexsat",
           "LQR_FREQUENCY_RANGE", "ProgressCallback"]

#: Range of the rigid-body LQR natural frequency (q / (r J^2))^(1/4) [rad/s]: that of a PD's
#: natural frequency in a scene (spacecraft.scene.read.RANGES["pd.frequency"]).
LQR_FREQUENCY_RANGE = (1e-5, 1e3)

# Folders of flexsat's packages: an exception raised by code in them is a checked condition of
# our API (its message names the parameter), one raised deeper (numpy, scipy) is not.
# (fmu located without importing it: a run without FMUs does not load the FMU toolchain)
_OUR_FOLDERS = tuple(Path(p.__file__).resolve().parent for p in (appendages, controllers)) + (
    Path(__file__).resolve().parents[1] / "fmu", Path(__file__).resolve().parent)

ProgressCallback = Callable[[str], None]



@dataclasses.dataclass
class RunStats:
    """Work counters kept by the runner and the report writer (proof of what was skipped).

    Attributes
    ----------
    fmu_builds : int
        FMUs compiled.
    plots : int
        PNG figures written.
    exact_reference_evaluations : int
        Calls into the exact distributed-beam reference (exact coupled frequencies, exact
        frequency responses, equivalence tables against the exact W).
    chain_fits : int
        Chains fitted to beams.
    pd_designs, lqr_designs : int
        Controllers tuned.
    simulations : int
        Time responses computed.
    simulator_setups : int
        Discretisations (matrix exponentials + modal forms) built; one per closed loop.
    eigendecompositions : int
        Spacecraft assemblies whose modes were computed (one per model set).
    plant_builds : int
        State-space plants built (each reused for every controller).
    tip_deflection_outputs, root_load_outputs : int
        Such outputs in the plants built.
    modes_kept, modes_dropped : int
        Modes of the truth plant kept and dropped by pruning (elastic and rigid).
    cache_hits : int
        Requests answered from the run's caches.
    basilisk_runs : int
        Manoeuvres run in Basilisk.
    pointing_analyses : int
        Pointing budgets computed (covariance analyses under the sensors' noise).
    seconds : dict
        Wall time per stage [s] (informative, never asserted).
    """

    fmu_builds: int = 0
    plots: int = 0
    exact_reference_evaluations: int = 0
    chain_fits: int = 0
    pd_designs: int = 0
    lqr_designs: int = 0
    simulations: int = 0
    simulator_setups: int = 0
    eigendecompositions: int = 0
    plant_builds: int = 0
    tip_deflection_outputs: int = 0
    root_load_outputs: int = 0
    modes_kept: int = 0
    modes_dropped: int = 0
    cache_hits: int = 0
    pointing_analyses: int = 0
    basilisk_runs: int = 0
    seconds: dict = dataclasses.field(default_factory=dict)

    def as_dict(self) -> dict:
        """JSON-ready copy."""
        return dataclasses.asdict(self)



def raised_by_flexsat(exc: BaseException) -> bool:
    """True if ``exc`` was raised by code of flexsat's packages (a checked condition), not
    inside numpy, scipy or python-control."""
    tb = exc.__traceback__
    if tb is None:
        return False
    while tb.tb_next is not None:
        tb = tb.tb_next
    try:
        path = Path(tb.tb_frame.f_code.co_filename).resolve()
    except (OSError, ValueError):
        return False
    return any(path.is_relative_to(folder) for folder in _OUR_FOLDERS)


class TruthLoop:
    """A controller closed on a truth plant (:meth:`ModelBuilder.truth_loop`).

    Attributes
    ----------
    poles : ndarray, complex, 1/s
        Closed-loop poles (s-plane).
    verdict : controllers.SpilloverVerdict
        Its verdict with margins, computed when first read.
    """

    def __init__(self, poles: np.ndarray, verdict: Callable[[], object]):
        self.poles = poles
        self._verdict = verdict

    @functools.cached_property
    def verdict(self):
        return self._verdict()


@dataclasses.dataclass(frozen=True)
class GivenModels:
    """A Python user's own models of one spacecraft (``spacecraft.DesignLoop(truth=...)``).

    Attributes
    ----------
    truth : Spacecraft
        The model the loops are judged on.
    designs : dict of str to Spacecraft
        The models the controllers are tuned on, by label.
    exact : Spacecraft or None
        The spacecraft with its distributed appendages (exact frequency response).
    """

    truth: Spacecraft
    designs: dict
    exact: Spacecraft | None = None


class ModelBuilder:
    """The models of one scene (or a user's own, ``given``), built once and cached: beams,
    chains, truncations, spacecraft, plants, tuned controllers and their margins."""

    def __init__(self, scene: Scene, progress: ProgressCallback | None, stats: RunStats,
                 time_responses: bool = True, *, given: GivenModels | None = None):
        self.time_responses = time_responses
        self.scene = scene
        self.given = given
        self.progress = progress or (lambda message: None)
        self.stats = stats
        self._index = {a.name: k for k, a in enumerate(scene.appendages)}
        if given is not None:
            self.hub = given.truth.hub
        else:
            with self.scene_values("hub"):
                self.hub = Hub(scene.hub.mass, np.asarray(scene.hub.inertia, dtype=float)
                               if scene.three_axis else scene.hub.inertia)
        self._cache: dict = {}
        self._modal_spacecraft: set = set()
        # appendage -> {motion: modes kept at least}: what the tip-output rule added
        # (:meth:`tip_fidelity`), or what the scene pins beside a given n_modes
        # (``fidelity.modes_per_motion``)
        self.tip_floors: dict = scene.fidelity.pinned_floors()

    @property
    def three_axis(self) -> bool:
        """True for a three-axis spacecraft (a 3x3 hub inertia)."""
        return bool(self.hub.three_axis)

    @property
    def names(self) -> list[str]:
        """The appendages' names, in mount order."""
        if self.given is not None:
            return list(self.given.truth.names)
        return [a.name for a in self.scene.appendages]

    @property
    def variants(self) -> tuple:
        """Labels of the design models: one per fit criterion (or ``("design",)``), or the
        labels of a user's own design models."""
        if self.given is not None:
            return tuple(self.given.designs)
        return self.scene.design_variants

    def rigid_inertia(self):
        """The spacecraft's rigid-body inertia about its centre of mass [kg m^2] (a number,
        or the 3x3 tensor in hub axes): the same for every model of it."""
        return self.cached(("rigid inertia",), lambda: self.exact_spacecraft().inertia)

    # -- errors --------------------------------------------------------------------------------
    @contextlib.contextmanager
    def scene_values(self, key: str, what: str = ""):
        """Report an error of our API, raised by a call made with the scene's values at ``key``,
        as a SceneError naming that key (a user error); anything else passes unchanged."""
        try:
            yield
        except SceneError:
            raise
        except (ValueError, TypeError, FlexsatError) as exc:
            if not (isinstance(exc, FlexsatError) or raised_by_flexsat(exc)):
                raise  # numpy/scipy trouble with accepted values: a bug of ours
            raise SceneError(f"{self.scene.source}: {key}: {what}{exc}") from exc

    def key(self, spec: AppendageSpec, rest: str) -> str:
        """Key path of an appendage's sub-key: ``appendages[1].beam``."""
        return f"appendages[{self._index[spec.name]}].{rest}"

    # -- caching -------------------------------------------------------------------------------
    def cached(self, key, build):
        if key in self._cache:
            self.stats.cache_hits += 1
            return self._cache[key]
        value = build()
        self._cache[key] = value
        return value

    def stage(self, name: str):
        runner = self

        class _Stage:
            def __enter__(self):
                runner.progress(name)
                self.t0 = time.perf_counter()

            def __exit__(self, *exc):
                runner.stats.seconds[name] = (runner.stats.seconds.get(name, 0.0)
                                              + time.perf_counter() - self.t0)
        return _Stage()

    # -- appendage models ----------------------------------------------------------------------
    def beam(self, spec: AppendageSpec):
        """The appendage's structure, its exact model: a distributed beam (uniform, with a tip
        body, stepped, tapered) or its modal data (exact for the modes they hold)."""
        def build():
            with self.scene_values(self.key(spec, spec.structure.kind)):
                return spec.structure.build()
        return self.cached(("beam", spec.structure), build)

    def chain(self, spec: AppendageSpec, chain: ChainSpec):
        from appendages.chain import HingedChain

        which = "truth_chain" if chain is spec.truth_chain else "chain"

        def build():
            with self.scene_values(self.key(spec, which)):
                return built()

        def built():
            if chain.from_beam is None:
                # a three-axis chain's other motions: None (a planar scene's) is the default
                return HingedChain(chain.lengths, chain.masses, chain.inertias,
                                   chain.hinge_stiffnesses, hinge_dampings=chain.hinge_dampings,
                                   com_offsets=chain.com_offsets, root=chain.root,
                                   inertias_y=chain.inertias_y,
                                   hinge_stiffnesses_y=chain.hinge_stiffnesses_y,
                                   hinge_dampings_y=chain.hinge_dampings_y,
                                   torsional_inertias=chain.torsional_inertias,
                                   torsion_stiffnesses=chain.torsion_stiffnesses,
                                   torsion_dampings=chain.torsion_dampings,
                                   axial_stiffnesses=chain.axial_stiffnesses,
                                   axial_dampings=chain.axial_dampings)
            base = HingedChain.rfem(self.beam(spec), chain.n_bodies)
            if chain.root == "rigid":
                return base
            dampings = (np.zeros(base.hinge_stiffnesses.size) if base.hinge_dampings is None
                        else np.asarray(base.hinge_dampings))
            return HingedChain(base.lengths, base.masses, base.inertias,
                               np.concatenate([[chain.root_stiffness], base.hinge_stiffnesses]),
                               hinge_dampings=np.concatenate([[chain.root_damping], dampings]),
                               com_offsets=base.com_offsets, root="hinged")
        return self.cached(("chain", spec.name, id(chain)), build)

    def fit(self, spec: AppendageSpec, match: str):
        """Chain fitted to the appendage's structure, damped as it is
        (:func:`appendages.fit_chain`: stiffness-proportional hinge damping with the
        appendage's damping ratio at its first cantilever frequency; in a three-axis scene
        :func:`appendages.fit_chain_3d`: the bending fit in both planes, torsion and axial
        motion, each damped as the appendage)."""
        def build():
            from appendages.equivalence import fit_chain
            from appendages.fit3d import fit_chain_3d

            beam = self.beam(spec)
            self.stats.chain_fits += 1
            with warnings.catch_warnings(), self.scene_values(
                    self.key(spec, "fit"), f"cannot fit a chain (match = {match!r}): "):
                warnings.simplefilter("ignore", RuntimeWarning)
                if self.three_axis:
                    return fit_chain_3d(beam, spec.fit.n_bodies, match=match)
                return fit_chain(beam, spec.fit.n_bodies, match=match)
        # identical beams (two symmetric wings) share one fit
        return self.cached(("fit", spec.structure, spec.fit.n_bodies, match, self.three_axis),
                           build)

    def undamped_beam(self, spec: AppendageSpec):
        """The appendage's beam without damping (for the choice of the number of modes)."""
        def build():
            return self.beam(spec).undamped()
        return self.cached(("undamped beam", spec.beam), build)

    def seen_motions(self) -> tuple:
        """The motions of a three-axis beam that the run's reported outputs see and that a
        truncation chosen from the tolerance must keep a mode of: with ``outputs.tip_deflection``
        bending in both planes (``<name>_tip_deflection_y``, ``_z``) and torsion
        (``<name>_tip_twist``); with ``outputs.root_loads`` also the axial motion (the root
        force along the appendage, ``<name>_root_force_x``). Empty for a planar scene, without
        those outputs, or with ``fidelity.n_modes`` given alone (the user's count is kept as it
        is, and a tip output it leaves without a mode is warned about:
        :func:`spacecraft.design.loop.unmodelled_outputs`). With ``fidelity.modes_per_motion``
        beside n_modes, the motions a tolerance run's tip outputs see (and axial with root
        loads) whatever the outputs: the pinned truth is the same with tip outputs on or off."""
        scene = self.scene
        outputs = scene.outputs
        fidelity = scene.fidelity
        if not self.three_axis:
            return ()
        pinned = fidelity.n_modes is not None and fidelity.modes_per_motion is not None
        if not pinned and (fidelity.n_modes is not None
                           or not (outputs.tip_deflection or outputs.root_loads)):
            return ()
        return ("xy", "xz", "torsion") + (("axial",) if outputs.root_loads else ())

    def truncation(self, beam, n_modes: int, floors: dict | None = None):
        """``beam`` truncated by the scene's method: its ``n_modes`` lowest (planar: bending)
        modes; in a three-axis scene that reports tip outputs, with ``n_modes`` chosen from the
        tolerance (or given with ``fidelity.modes_per_motion``), also the lowest mode of every
        motion they see (:meth:`seen_motions`) that the beam has, so that no tip output of the
        truth model reads 0 for want of a mode: a uniform beam keeps those and the ``n_modes``
        lowest of the rest (:func:`spacecraft.design.fidelity.motion_counts`); a beam whose
        modes are ranked together (a tip body, segments) keeps its ``k0 - 1 + n_modes`` lowest
        modes, k0 the fewest lowest modes that move every seen tip motion
        (:meth:`coupled_floor`). Either way each added n adds a mode.

        ``floors`` (what the tip-output rule adds, :meth:`tip_fidelity`, or the scene pins,
        ``fidelity.modes_per_motion``): a uniform three-axis beam keeps at least
        ``floors[motion]`` modes of each motion (and the ``n_modes`` lowest beyond them); a
        planar beam ``floors["bending"]`` modes more, a three-axis beam whose modes are ranked
        together ``floors["coupled"]`` lowest modes more."""
        method = self.scene.fidelity.method
        seen = self.seen_motions()
        floors = floors or {}
        if not seen and not (self.three_axis and floors):
            return beam.truncated(n_modes + floors.get("bending", 0), method=method)
        if getattr(beam, "is_uniform", False):
            counts = motion_counts(beam, n_modes, method, seen, floors)
            # n_modes of the truncation is its planar (x-y) model's: the x-y part of this one
            return beam.truncated(max(1, counts["xy"]), method=method, modes_per_motion=counts)
        return beam.truncated(self.coupled_floor(beam) - 1 + n_modes + floors.get("coupled", 0),
                              method=method)

    def floors_key(self, floors: dict | None = None) -> tuple:
        """A cache key of per-appendage floors (default: :attr:`tip_floors`)."""
        floors = self.tip_floors if floors is None else floors
        return tuple(sorted((name, tuple(sorted(f.items()))) for name, f in floors.items() if f))

    def tip_outputs(self) -> dict:
        """The reported outputs of truncated beams the tip-output rule holds, output name ->
        ((appendage, motion), unit): with ``fidelity.n_modes`` chosen from the tolerance, the
        tip deflections (and twists) with ``outputs.tip_deflection`` and the root loads with
        ``outputs.root_loads``, of every appendage whose truth is a truncated beam. A motion
        is a uniform three-axis beam's (:data:`spacecraft.design.fidelity.OUTPUT_MOTIONS`),
        ``"coupled"`` for a three-axis beam whose modes are ranked together, ``"bending"``
        in the plane."""
        scene = self.scene
        out = {}
        if self.given is not None or scene.fidelity.n_modes is not None:
            return out
        wanted = (("_tip_deflection", "_tip_twist") if scene.outputs.tip_deflection else ()) + (
            ("_root_force", "_root_moment") if scene.outputs.root_loads else ())
        for a in scene.appendages:
            if a.truth != "beam":
                continue
            uniform = getattr(self.beam(a), "is_uniform", False)
            for suffix, (motion, unit) in OUTPUT_MOTIONS.items():
                three = suffix[-2:] in ("_x", "_y", "_z") or suffix == "_tip_twist"
                if three != self.three_axis or not suffix.startswith(wanted):
                    continue
                if self.three_axis and not uniform:
                    motion = "coupled"
                elif self.three_axis and motion == "axial" and self.beam(a).axial_rod() is None:
                    continue
                elif self.three_axis and motion == "torsion" and self.beam(a).torsion_rod() is None:
                    continue
                out[a.name + suffix] = ((a.name, motion), unit)
        return out

    def coupled_floor(self, beam) -> int:
        """The fewest lowest modes of a three-axis beam whose modes are ranked together (a tip
        body, segments) that move every tip motion :meth:`seen_motions` names (a tip row of
        its root model with a non-zero entry), searched up to the largest truncation the
        read-time count lets the loop hold (:meth:`truncation_cap`); 1 when none up to there
        moves them all (the warning ``truth_output_unmodelled`` then names what stays
        unmoved)."""
        rows = {"xy": 0, "xz": 1, "torsion": 2}

        def build():
            method = self.scene.fidelity.method
            wanted = [rows[m] for m in self.seen_motions() if m in rows]
            for k in range(1, self.truncation_cap() + 1):
                with self.scene_values("fidelity"):
                    tip = beam.truncated(k, method=method).root_model(6).tip_rows
                if all(np.asarray(tip[i]).any() for i in wanted):
                    return k
            return 1
        return self.cached(("coupled floor", id(beam)), build)

    def truth_modes_per_motion(self, n_modes: int | None) -> dict:
        """Modes per motion (``xy``, ``xz``, ``torsion``, ``axial``) of each three-axis
        truncated truth beam whose motions are separate (a beam whose modes are ranked
        together: ``{"lowest coupled modes": k}``), by appendage name (empty for a planar scene
        or without truncated beams)."""
        if not self.three_axis or n_modes is None or self.given is not None:
            return {}
        out = {}
        for a in self.scene.appendages:
            if a.truth != "beam":
                continue
            model = self.truth_model(a, n_modes)
            out[a.name] = (model.modes_per_motion if getattr(self.beam(a), "is_uniform", False)
                           else {"lowest coupled modes": int(model.n_modes)})
        return out

    def truth_model(self, spec: AppendageSpec, n_modes: int | None):
        if spec.truth == "modal":
            return self.beam(spec)  # all the modes of the data: FE-exact
        if spec.truth == "beam":
            floors = self.tip_floors.get(spec.name)

            def build():
                with self.scene_values("fidelity"):
                    return self.truncation(self.beam(spec), n_modes, floors)
            return self.cached(("truncated", spec.name, n_modes, self.scene.fidelity.method,
                                self.floors_key({spec.name: floors or {}})), build)
        return self.chain(spec, spec.truth_chain or spec.chain)

    def design_model(self, spec: AppendageSpec, variant: str, n_modes: int | None):
        if spec.design == "fit":
            match = variant if variant in spec.fit.match else spec.fit.match[0]
            return self.fit(spec, match)
        if spec.design == "chain":
            return self.chain(spec, spec.chain)
        return self.truth_model(spec, n_modes)

    def spacecraft(self, key, models) -> Spacecraft:
        def build():
            mounts = []
            for a, model in zip(self.scene.appendages, models):
                with self.scene_values(f"appendages[{self._index[a.name]}]",
                                       "cannot mount it: "):
                    mounts.append(Mount(model, a.position, orientation=np.array(a.orientation),
                                        name=a.name) if self.three_axis else
                                  Mount(model, a.position, a.direction, name=a.name))
            return Spacecraft(self.hub, mounts)
        return self.cached(("spacecraft", key), build)

    def design_key(self, variant: str, n_modes: int | None) -> tuple:
        """Cache key of a design variant's models: n_modes matters only when an appendage is
        designed on its truth model (``design = "truth"``)."""
        depends = any(a.design == "truth" for a in self.scene.appendages)
        return ("design", variant, n_modes if depends else None)

    def design_spacecraft(self, variant: str, n_modes: int | None) -> Spacecraft:
        """The spacecraft of a design variant (its design model of each appendage)."""
        if self.given is not None:
            return self.given.designs[variant]
        models = [self.design_model(a, variant, n_modes) for a in self.scene.appendages]
        return self.spacecraft(self.design_key(variant, n_modes), models)

    def truth_spacecraft(self, n_modes: int | None) -> Spacecraft:
        """The truth model: each appendage's truth model (beams truncated to ``n_modes``)."""
        if self.given is not None:
            return self.given.truth
        models = [self.truth_model(a, n_modes) for a in self.scene.appendages]
        return self.spacecraft(("truth", n_modes, self.floors_key()), models)

    def design_plant(self, variant: str, n_modes: int | None):
        """The plant the controllers are tuned on (tip deflections when the LQR weighs them)."""
        lqr = self.scene.controller.lqr
        return self.plant(self.design_spacecraft(variant, n_modes),
                          self.design_key(variant, n_modes),
                          tip=lqr is not None and lqr.deflection_weight is not None,
                          prune=self.scene.fidelity.prune)

    def simulation_plant(self, which: str, variant: str, n_modes: int | None):
        """The plant a manoeuvre is simulated on: the truth model (``which = "truth"``) or a
        design model, with the outputs and disturbance inputs the specification asks for."""
        scene = self.scene
        m = scene.manoeuvre
        if which == "truth":
            sc, key = self.truth_spacecraft(n_modes), ("truth", n_modes)
        else:
            sc, key = self.design_spacecraft(variant, n_modes), self.design_key(variant, n_modes)
        return self.plant(sc, key, tip=scene.outputs.tip_deflection,
                          root_loads=scene.outputs.root_loads,
                          disturbances=m is not None and m.disturbance is not None,
                          prune=scene.fidelity.prune)[0]

    def tuned(self, variant: str, kind: str, n_modes: int | None):
        """The controller ``kind`` tuned on a design variant (:func:`spacecraft.design.tuning.tune`),
        once per design plant; a failure is a SceneError naming controller.<kind>."""
        from .tuning import tune

        def build():
            plant, _ = self.design_plant(variant, n_modes)
            with self.scene_values(f"controller.{kind}", f"cannot tune on the design model "
                                                         f"({variant}): "):
                if kind == "pd":
                    self.stats.pd_designs += 1
                else:
                    self.stats.lqr_designs += 1
                m = self.scene.manoeuvre
                return tune(kind, plant, self.scene.controller,
                            feedforward=m is not None and m.feedforward)
        return self.cached(("tuned", self.design_key(variant, n_modes), kind), build)

    def design_margins(self, variant: str, kind: str, n_modes: int | None, controller=None):
        """:func:`controllers.margins` of a controller on its design plant (once): the one
        tuned there, or ``controller``."""
        def build():
            plant, _ = self.design_plant(variant, n_modes)
            K = (controller if controller is not None
                 else self.tuned(variant, kind, n_modes).controller)
            with np.errstate(all="ignore"), warnings.catch_warnings(), quiet_unit_slips():
                warnings.simplefilter("ignore", RuntimeWarning)
                return controllers.margins(plant, K, **loop_delay(self.scene.controller))
        return self.cached(("design margins", self.design_key(variant, n_modes), kind,
                            None if controller is None else id(controller)), build)

    def truth_spillover(self, plant, controller, *, delayed: bool = False):
        """:func:`controllers.spillover` of a controller on a truth plant, once per (plant,
        controller) of the run; ``delayed``: with the scene's loop delay (the run's verdict;
        the fidelity rule compares the loops without it)."""
        delay = loop_delay(self.scene.controller) if delayed else {}

        def build():
            with np.errstate(all="ignore"), warnings.catch_warnings(), quiet_unit_slips():
                warnings.simplefilter("ignore", RuntimeWarning)
                return controllers.spillover(plant, controller, **delay)
        return self.cached(("spillover", id(plant), id(controller), tuple(delay.items())),
                           build)

    def truth_loop(self, plant, controller) -> "TruthLoop":
        """A controller closed on a truth plant: its poles at once, its verdict when read."""
        def build():
            return TruthLoop(closed_loop_poles(controllers.close_loop(plant, controller)),
                             lambda: self.truth_spillover(plant, controller))
        return self.cached(("truth loop", id(plant), id(controller)), build)

    def truth_plant(self, n_modes: int | None):
        """The truth plant of the verdicts (torque to theta, omega; pruned as the scene says)."""
        return self.plant(self.truth_spacecraft(n_modes), ("truth", n_modes, self.floors_key()),
                          prune=self.scene.fidelity.prune)[0]

    def truth_loops(self, n_modes: int) -> dict:
        """(variant, kind) -> :class:`TruthLoop` of every loop of the scene on the truth model
        with n_modes modes per beam."""
        plant = self.truth_plant(n_modes)
        return {(variant, kind): self.truth_loop(
                    plant, self.tuned(variant, kind, n_modes).controller)
                for variant in self.variants for kind in self.scene.controller.types}

    def plant(self, sc: Spacecraft, key, *, tip=False, root_loads=False, disturbances=False,
              prune=True):
        """Plant with the requested signals, pruned if asked (built once per signal set)."""
        def build():
            if id(sc) not in self._modal_spacecraft:
                self._modal_spacecraft.add(id(sc))
                self.stats.eigendecompositions += 1
            self.stats.plant_builds += 1
            full = sc.plant(tip_deflection=tip, root_loads=root_loads, disturbances=disturbances,
                            prune=prune)
            n_total = sc.modes()[0].size
            kept = full.nstates // 2
            if tip:   # planar: the deflection; three axes: both planes and the twist
                self.stats.tip_deflection_outputs += (3 if sc.three_axis else 1) * len(sc.mounts)
            if root_loads:   # planar: force and moment; three axes: three of each
                self.stats.root_load_outputs += (6 if sc.three_axis else 2) * len(sc.mounts)
            return full, {"modes_total": int(n_total), "modes_kept": int(kept),
                          "modes_dropped": int(n_total - kept)}
        return self.cached(("plant", key, tip, root_loads, disturbances, prune), build)

    # -- exact reference -----------------------------------------------------------------------
    def exact_spacecraft(self) -> Spacecraft:
        """The spacecraft with its distributed appendages (chains where the truth is one)."""
        if self.given is not None:
            return self.given.exact if self.given.exact is not None else self.given.truth
        models = [self.beam(a) if a.truth in ("beam", "modal") else self.truth_model(a, None)
                  for a in self.scene.appendages]
        return self.spacecraft("exact", models)

    def exact_frequencies(self, k: int) -> np.ndarray:
        def build():
            self.stats.exact_reference_evaluations += 1
            return self.exact_spacecraft().natural_frequencies(k, exact=True)
        return self.cached(("exact_frequencies", k), build)

    # -- the run -------------------------------------------------------------------------------
    def design_bandwidth(self, inertia) -> float:
        """Rigid-body closed-loop natural frequency of the fastest controller [rad/s] (three
        axes: about the fastest axis)."""
        from controllers import natural_frequency_from_bandwidth

        c = self.scene.controller
        values = []
        if c.pd is not None:
            values.append(c.pd.natural_frequency if c.pd.natural_frequency is not None
                          else natural_frequency_from_bandwidth(c.pd.bandwidth, c.pd.damping))
        if c.lqr is not None:
            values.append(self.lqr_frequency(inertia))
        return max(values)

    def lqr_frequency(self, inertia) -> float:
        """Rigid-body LQR natural frequency [rad/s] (three axes: about the axis of least
        inertia, the fastest), refused outside LQR_FREQUENCY_RANGE about any axis."""
        lqr = self.scene.controller.lqr
        # three axes: the same weights on every principal axis, each with its moment
        moments = (np.linalg.eigvalsh(np.asarray(inertia, dtype=float)) if self.three_axis
                   else [float(inertia)])
        lo, hi = LQR_FREQUENCY_RANGE
        values = []
        for J in moments:
            # rigid-body LQR poles: w = (q / (r J^2))^(1/4) (Anderson & Moore, sec. 5.2),
            # formed as (q/r)^(1/4) / sqrt(J): no overflow of J^2
            w = (lqr.attitude_weight / lqr.torque_weight) ** 0.25 / math.sqrt(J)
            if not lo <= w <= hi:
                axis = " (a principal moment)" if self.three_axis else ""
                raise SceneError(
                    f"{self.scene.source}: controller.lqr: the weights give a rigid-body "
                    f"closed-loop frequency (attitude_weight / (torque_weight J^2))^(1/4) = "
                    f"{w:.3g} rad/s with J = {J:.4g} kg m^2{axis}, outside [{lo:g}, {hi:g}] "
                    "rad/s; change attitude_weight or torque_weight")
            values.append(w)
        return max(values)

    def choose_fidelity(self) -> tuple[int | None, FidelityChoice | None]:
        scene = self.scene
        if not scene.has_beam_truth:
            return None, None
        if scene.fidelity.n_modes is not None:
            return scene.fidelity.n_modes, None
        with self.stage("choosing the number of modes"):
            inertia = self.rigid_inertia()
            bandwidth = self.design_bandwidth(inertia)

            # The choice compares undamped models (natural frequencies are undamped, and the
            # low-band gain depends on damping only at second order): trial truncations of
            # undamped beams skip the damping projection, and only the chosen one is built
            # with damping.
            def truncated(n):
                models = [self.truncation(self.undamped_beam(a), n)
                          if a.truth == "beam" else self.truth_model(a, n)
                          for a in scene.appendages]
                sc = self.spacecraft(("undamped truth", n), models)
                plant, _ = self.plant(sc, ("undamped truth", n), prune=scene.fidelity.prune)
                frequencies = sc.modes()[0][sc.n_rigid:]
                return frequencies, plant

            def exact_response(omega):
                self.stats.exact_reference_evaluations += 1
                models = [self.undamped_beam(a) if a.truth == "beam" else
                          self.truth_model(a, None) for a in scene.appendages]
                frd = self.spacecraft("undamped exact", models).frequency_response(omega)
                return np.moveaxis(np.asarray(frd.frdata), -1, 0)   # (omega, m, m)

            with self.scene_values("fidelity.tolerance"):
                choice = choose_n_modes(truncated, self.exact_frequencies, exact_response,
                                        bandwidth=bandwidth, tolerance=scene.fidelity.tolerance,
                                        bandwidth_factor=scene.fidelity.bandwidth_factor,
                                        method=scene.fidelity.method,
                                        first_zero=self.first_clamped_frequency(),
                                        n_max=self.max_modes())
        if self.tip_outputs():
            with self.stage("holding the tip outputs"):
                choice = self.tip_fidelity(choice)
        with self.stage("converging the closed loops"):
            choice = self.closed_loop_fidelity(choice, bandwidth)
        return choice.n_modes, choice

    def tip_fidelity(self, choice: FidelityChoice) -> FidelityChoice:
        """The open-loop choice with the modes the reported tip outputs need
        (:func:`spacecraft.design.fidelity.refine_for_tip_outputs`): at the chosen n, each tip
        output's (and root load's) response per hub torque on the open-loop rule's band,
        undamped, is compared between the truncation and one with a mode more of the motion
        that moves it (per appendage), and modes of that motion are added until the change is
        within the tolerance; sets :attr:`tip_floors` (the closed-loop rule then adds modes
        from there) and records the search in ``choice.tip``. A stiff motion's one mode with
        the Craig-Bampton constraint modes misses the static flexibility of its higher modes
        (a uniform rod's tip twist under a uniform load: 32/pi^3 = 1.032 of the exact one),
        which a slew's quasi-static tip figures show in full."""
        scene = self.scene
        n = choice.n_modes
        outputs = self.tip_outputs()
        units = {name: unit for name, (_, unit) in outputs.items()}
        cap = self.max_modes()
        specs = {a.name: a for a in scene.appendages}
        inputs = ["torque_x", "torque_y", "torque_z"] if self.three_axis else ["torque"]
        omega = np.geomspace(choice.band[0], choice.band[1], 40)

        order = {a.name: i for i, a in enumerate(scene.appendages)}

        def per_beam(floors: dict) -> dict:
            # in the scene's order of appendages, motions sorted: the floors' order (in the
            # report and results.json) does not follow a set's, which varies per process
            out: dict = {}
            for (name, motion), k in sorted(floors.items(),
                                            key=lambda item: (order[item[0][0]], item[0][1])):
                out.setdefault(name, {})[motion] = k
            return out

        def plant(floors: dict):
            beams = per_beam(floors)

            def build():
                models = [self.truncation(self.undamped_beam(a), n, beams.get(a.name))
                          if a.truth == "beam" else self.truth_model(a, n)
                          for a in scene.appendages]
                sc = self.spacecraft(("undamped tip", n, self.floors_key(beams)), models)
                return self.plant(sc, ("undamped tip", n, self.floors_key(beams)),
                                  tip=scene.outputs.tip_deflection,
                                  root_loads=scene.outputs.root_loads,
                                  prune=scene.fidelity.prune)[0]
            with self.scene_values("fidelity"):
                return build()

        def add(floors: dict, motions: set) -> dict:
            out = dict(floors)
            for name, motion in sorted(motions):
                beam = self.undamped_beam(specs[name])
                if motion in ("bending", "coupled"):
                    if n + floors.get((name, motion), 0) + 1 <= cap:
                        out[(name, motion)] = floors.get((name, motion), 0) + 1
                    continue
                mine = {m: k for (b, m), k in floors.items() if b == name}
                counts = motion_counts(beam, n, scene.fidelity.method, self.seen_motions(),
                                       mine)
                if counts[motion] + 1 <= cap:
                    out[(name, motion)] = counts[motion] + 1
            return out

        def compare(before: dict, after: dict) -> dict:
            return output_changes(plant(before), plant(after), omega, inputs, units)

        motions = {motion for motion, _ in outputs.values()}
        floors, record = refine_for_tip_outputs(compare, add, lambda o: outputs[o][0], motions,
                                                tolerance=scene.fidelity.tolerance)
        self.tip_floors = per_beam(floors)
        record = {"band": list(choice.band), "n_modes": n, **record,
                  "floors": self.tip_floors}
        return dataclasses.replace(choice, tip=record)

    def closed_loop_fidelity(self, choice: FidelityChoice, bandwidth: float) -> FidelityChoice:
        """The open-loop choice refined until the scene's closed loops converge
        (:func:`spacecraft.design.fidelity.refine_for_closed_loop`); the band of poles compared is
        bandwidth_factor x the fastest crossover on the design models (as the run's check of
        the truth model's resolution), or the first exact coupled frequency above
        bandwidth_factor x the bandwidth if higher."""
        scene = self.scene
        if not scene.controller.types:
            return choice
        crossovers = [w for variant in self.variants for kind in scene.controller.types
                      for w in crossover_frequencies(self.design_margins(variant, kind,
                                                                         choice.n_modes))]
        band = max(scene.fidelity.bandwidth_factor * max([bandwidth] + crossovers),
                   float(choice.reference_frequencies[-1]))
        n, record = refine_for_closed_loop(self.truth_loops, choice.n_modes,
                                           tolerance=scene.fidelity.tolerance, band=band,
                                           n_max=self.max_modes())
        return dataclasses.replace(choice, n_modes=n, open_loop_n_modes=choice.n_modes,
                                   closed_loop=record)

    def max_modes(self) -> int:
        """Most modes per beam (n) the search from a tolerance may try: fidelity.MAX_MODES,
        within limits.modes and the loop size limits.states allows. A three-axis beam whose
        modes are ranked together (:meth:`truncation`) is counted with the modes it keeps
        beyond n, ``k0 - 1`` (:meth:`coupled_floor`) and its pinned ones, which only its
        modes tell; the other beams as :meth:`truncation_cap` counts them."""
        scene = self.scene
        cap = self.truncation_cap()
        coupled = self.coupled_beams()
        if not coupled:
            return cap
        kept = {a.name: self.floor_beyond_n() for a in scene.appendages if a.truth == "beam"}
        for a in coupled:
            kept[a.name] = (self.coupled_floor(self.beam(a)) - 1
                            + self.tip_floors.get(a.name, {}).get("coupled", 0))
        while cap > 1:
            trial = scene.replace(fidelity=dataclasses.replace(
                scene.fidelity, n_modes=cap, modes_per_motion=None))
            if estimate_cost(trial, kept=kept).loop_states <= scene.limits.states:
                break
            cap -= 1
        return cap

    def truncation_cap(self) -> int:
        """Most modes per beam within fidelity.MAX_MODES, limits.modes and the loop size
        limits.states allows by the read-time count (:func:`spacecraft.scene.limits.estimate_cost`,
        counting, in three axes, a mode more per motion a reported output sees and the modes
        the tip-output rule added: :meth:`floor_beyond_n`)."""
        scene = self.scene
        cap = min(MAX_MODES, scene.limits.modes)
        floor = self.floor_beyond_n()
        while cap > 1:
            trial = scene.replace(fidelity=dataclasses.replace(
                scene.fidelity, n_modes=cap + floor, modes_per_motion=None))
            if estimate_cost(trial).loop_states <= scene.limits.states:
                break
            cap -= 1
        return cap

    def floor_beyond_n(self) -> int:
        """Modes a truncation keeps beyond n by the read-time count: one per motion a reported
        output sees (:meth:`seen_motions`) and the modes the tip-output rule added beyond the
        one a motion has anyway (the largest over the beams)."""
        seen = self.seen_motions()
        return len(seen) + max((sum(k - (m in seen) for m, k in f.items())
                                for f in self.tip_floors.values()), default=0)

    def coupled_beams(self) -> list:
        """The appendages whose truth is a three-axis beam with modes ranked together (a tip
        body, segments) truncated by its lowest modes (:meth:`truncation`): with motions a
        reported output sees or modes pinned."""
        if not self.three_axis or self.given is not None:
            return []
        seen = self.seen_motions()
        return [a for a in self.scene.appendages
                if a.truth == "beam" and not getattr(self.beam(a), "is_uniform", False)
                and (seen or self.tip_floors.get(a.name))]

    def check_loop_states(self, n_modes: int | None, *, variants=None, kinds=None,
                          controller=None, models: tuple = ("design", "truth")) -> int:
        """The states of the largest closed loop the run builds, refused over limits.states.

        Counted on the plants as built (the models with the modes they keep: a beam whose
        modes are ranked together keeps what its modes ask, which the read-time estimate
        cannot know), the controllers as they will be
        (:func:`spacecraft.scene.limits.controller_states`, or ``controller``'s own states)
        and a delayed loop's delay line (:func:`spacecraft.scene.limits.delay_states`),
        before any controller is tuned or loop closed, simulated or judged.

        Parameters
        ----------
        n_modes : int or None
            Modes per truncated beam of the truth model.
        variants, kinds : sequence of str, optional
            The design variants and controller types closed (default: the scene's).
        controller : control.StateSpace, optional
            A controller given instead of one tuned (a sweep's nominal controller).
        models : tuple of str
            The models the controllers are closed on: ``"design"`` and/or ``"truth"``.

        Returns
        -------
        int
            States of the largest closed loop (0 for a user's own models: not checked).

        Raises
        ------
        SceneError
            Over ``limits.states``, naming the appendage and the key that drive the size, the
            states and the limit, and what to do.
        """
        if self.given is not None:
            return 0
        scene = self.scene
        kinds = scene.controller.types if kinds is None else kinds
        truth = (self.simulation_plant("truth", None, n_modes).nstates if "truth" in models
                 else 0)
        delay = delay_states(scene)
        worst = (0, 0, "truth", None, None, 0)
        for variant in (self.variants if variants is None else variants):
            design = (self.simulation_plant("design", variant, n_modes).nstates
                      if "design" in models else 0)
            plant, which = (truth, "truth") if truth >= design else (design, "design")
            for kind in kinds:
                if controller is not None:
                    k = int(controller.nstates)
                else:
                    states = (self.design_plant(variant, n_modes)[0].nstates if kind == "lqr"
                              else 0)
                    k = controller_states(scene.controller, kind, states, self.three_axis)
                if plant + k + delay > worst[0]:
                    worst = (plant + k + delay, plant, which, variant, kind, k)
        total, plant, which, variant, kind, k = worst
        limit = scene.limits.states
        if total <= limit:
            return total
        if delay > plant:
            c = scene.controller
            step = "the sample time" if c.sample_time is not None else "manoeuvre.step"
            key, why, advice = ("controller.delay", f"the delay line holds the last "
                                f"{delay // (3 if self.three_axis else 1)} commands of each "
                                f"torque (the delay in steps of {step})",
                                f"shorten controller.delay or lengthen {step}")
        else:
            key, why, advice = self.size_driver(which, variant, n_modes)
        model = "truth model" if which == "truth" else f"design model ({variant})"
        raise SceneError(
            f"{scene.source}: {key}: the closed loop of the {kind.upper()} on the {model} "
            f"would have {total} states ({plant} of the plant, {k} of the controller"
            + (f", {delay} of the delay line" if delay else "") + "), over "
            f"the limit {limit} (limits.states, states of the largest closed loop): {why}; "
            f"{advice}, or if you really want more raise it: [limits] states = N in the "
            "scene, or --limit states=N")

    def size_driver(self, which: str, variant: str | None, n_modes: int | None):
        """The appendage that contributes most coordinates to a model (``which``: "truth" or
        "design") of the run: (the scene key behind its size, why it is that large, what to
        do), for :meth:`check_loop_states`."""
        scene = self.scene
        sc = (self.truth_spacecraft(n_modes) if which == "truth"
              else self.design_spacecraft(variant, n_modes))
        names = sc.second_order_model().coordinate_names
        counts = {a.name: sum(c.startswith(f"{a.name}.") for c in names)
                  for a in scene.appendages}
        spec = max(scene.appendages, key=lambda a: counts[a.name])
        name, size = spec.name, counts[spec.name]
        kind = spec.truth if which == "truth" else spec.design
        if kind == "truth":
            kind = spec.truth
        if kind != "beam":
            dof, rest = appendage_dof(spec, which, n_modes, three_axis=self.three_axis)
            key = self.key(spec, rest)
            return (key, f"appendage {name!r} has {size} coordinates ({rest})",
                    f"lower {key}")
        fidelity = scene.fidelity
        pinned = fidelity.pinned_floors().get(name)
        n_key = ("fidelity.n_modes" if fidelity.n_modes is not None
                 else "fidelity.tolerance")
        if spec in self.coupled_beams():
            beam = self.beam(spec)
            k0 = self.coupled_floor(beam)
            extra = self.tip_floors.get(name, {}).get("coupled", 0)
            body = getattr(spec.beam, "tip", None) is not None
            key = self.key(spec, "tip" if body else spec.structure.kind)
            ranked = "a tip body" if body else "segments"
            seen = ", ".join(self.seen_motions())
            why = (f"appendage {name!r} keeps {size} modes: "
                   f"the {k0} lowest, the fewest that move every tip motion it must keep a "
                   f"mode of ({seen}; its modes are ranked together: {ranked}), and n_modes - 1 "
                   f"= {n_modes - 1} more"
                   + (f" and {extra} pinned (fidelity.modes_per_motion.{name}.coupled)"
                      if extra else ""))
            if fidelity.modes_per_motion is not None:
                advice = ("pin fewer modes (fidelity.n_modes, fidelity.modes_per_motion), or "
                          "leave fidelity.modes_per_motion out (no mode of every motion kept)")
            else:
                advice = ("report fewer outputs (outputs.tip_deflection, outputs.root_loads: "
                          "no mode of every motion kept) or ask for fewer modes "
                          f"({n_key})")
            return key, why, advice
        key = f"fidelity.modes_per_motion.{name}" if pinned else n_key
        return (key, f"appendage {name!r} keeps {size} modes",
                "pin fewer modes (fidelity.n_modes, fidelity.modes_per_motion)")

    def first_clamped_frequency(self) -> float:
        """Lowest clamped-root frequency of the appendages [rad/s] (first zero of theta/torque)."""
        values = []
        for a in self.scene.appendages:
            if a.truth == "beam":
                if self.three_axis:
                    values.append(float(clamped_frequencies(self.beam(a), 0.0,
                                                            three_axis=True)[0]))
                else:
                    values.append(float(self.beam(a).cantilever_frequencies(1)[0]))
            elif a.truth == "modal":
                values.append(float(self.beam(a).frequencies[0]))
        return min(values, default=math.inf)


    def exact_grid(self, *, points_per_decade: int = POINTS_PER_DECADE,
                   points_per_mode: int = POINTS_PER_MODE) -> np.ndarray:
        """Frequencies [rad/s] of the exact reference, every coupled mode resolved: the
        module's :func:`exact_grid` of the exact spacecraft about the design bandwidth, its
        locating truncations built once for the run."""
        def build():
            wb = self.design_bandwidth(self.rigid_inertia())
            return exact_grid(self.exact_spacecraft(), wb, points_per_decade=points_per_decade,
                              points_per_mode=points_per_mode, locating=self.locating_spacecraft())
        return self.cached(("exact grid", points_per_decade, points_per_mode), build)

    def locating_spacecraft(self) -> Spacecraft:
        """The finite spacecraft that located the modes of :meth:`exact_grid`
        (:func:`locating_spacecraft` up to its top): it locates the resonances of the exact
        loops too (:func:`spacecraft.design.verdicts.exact_loop_verdict`)."""
        def build():
            w_hi = 1e3 * self.design_bandwidth(self.rigid_inertia())
            return locating_spacecraft(self.exact_spacecraft(), w_hi, locator=self._locator)
        return self.cached(("locating spacecraft",), build)

    def _locator(self, appendage, w_hi: float, three_axis: bool):
        """:func:`locator_model`, built once per appendage for the run (identical wings share
        it)."""
        return self.cached(("locator", id(appendage), w_hi, three_axis),
                           lambda: locator_model(appendage, w_hi, three_axis))

    def exact_reference_frd(self, **grid):
        """Exact attitudes and rates per torque of the spacecraft with its distributed
        appendages, as an FRD on :meth:`exact_grid` (``grid``: its options): planar outputs
        ``theta``, ``omega`` per ``torque``; three axes ``theta_x/_y/_z``, ``omega_x/_y/_z``
        per ``torque_x/_y/_z`` (through each appendage's W6)."""
        def build():
            omega = self.exact_grid(**grid)
            self.stats.exact_reference_evaluations += 1
            return self.exact_spacecraft().frequency_response(omega, output="both")
        return self.cached(("exact frd", tuple(sorted(grid.items()))), build)

    def exact_verdict(self, controller, exact_frd=None):
        """The verdict of a continuous controller on the exact distributed spacecraft, with the
        scene's loop delay: :func:`spacecraft.design.verdicts.exact_loop_verdict` on the exact
        reference (``exact_frd``, default :meth:`exact_reference_frd`), planar or three-axis
        (MIMO Nyquist on det(I + L), loop-at-a-time and disk margins through W6), the
        resonances of a three-axis loop located on :meth:`locating_spacecraft`.

        Raises ValueError for a digital controller or a grid too narrow for the Nyquist
        criterion."""
        frd = exact_frd if exact_frd is not None else self.exact_reference_frd()
        m = 3 if self.three_axis else 1
        P = np.moveaxis(np.asarray(frd.frdata)[:m, :m], -1, 0)
        self.stats.exact_reference_evaluations += 1
        with quiet_unit_slips():
            return exact_loop_verdict(self.exact_spacecraft(), controller, frd.omega, theta=P,
                                      delay=self.scene.controller.total_delay,
                                      locating=self.locating_spacecraft() if m > 1 else None)
