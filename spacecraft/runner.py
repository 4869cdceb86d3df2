"""Run a scene: build only what it asks for, tune, close the loops, collect every number.

:func:`run` turns a :class:`~spacecraft.scene.Scene` into a :class:`RunResult`: the models
(truth: distributed beams truncated to the modes the scene's tolerance needs, or chains; design:
chains fitted to the beams), the controllers tuned on each design model, the slew responses of
design and truth loops with their metrics and verdicts, and the equivalence tables. The report
(:mod:`spacecraft.report`) writes files from it; FMUs and plots are built there.

Nothing the scene does not ask for is built. :class:`RunStats` counts the work the code did
(FMU builds, plots, exact-beam evaluations, LQR designs, simulations, modes kept and dropped...),
so tests can prove each skip. Expensive results are cached within a run: one chain fit per
(beam, criterion), one Spacecraft (one eigen-decomposition) per model set, one plant per signal
set, one simulator (matrix exponential) per closed loop.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import control
import numpy as np

import appendages
import controllers
import fmu
from appendages.interface import FlexsatError

from .fidelity import MAX_MODES, FidelityChoice, choose_n_modes
from .hub import Hub, Mount
from .coupling import Spacecraft
from .limits import estimate_cost
from .scene import AppendageSpec, ChainSpec, Scene, SceneError, load_scene

__all__ = ["RunStats", "RunResult", "run", "ProgressCallback", "equivalence_table", "FIT_LABELS",
           "raised_by_flexsat", "LQR_FREQUENCY_RANGE", "diverged_at", "warning_lines"]

#: Range of the rigid-body LQR natural frequency (q / (r J^2))^(1/4) [rad/s]: that of a PD's
#: natural frequency in a scene (spacecraft.scene.RANGES["pd.frequency"]).
LQR_FREQUENCY_RANGE = (1e-5, 1e3)

# Folders of flexsat's packages: an exception raised by code in them is a checked condition of
# our API (its message names the parameter), one raised deeper (numpy, scipy) is not.
_OUR_FOLDERS = tuple(Path(p.__file__).resolve().parent
                     for p in (appendages, controllers, fmu)) + (Path(__file__).resolve().parent,)

# Most distinct warnings kept in a run's results.
_MAX_WARNINGS = 20

ProgressCallback = Callable[[str], None]

# Frequency grid of the exact frequency-domain reference: this many points per decade, plus
# points packed across the half-power band of every exact coupled mode.
_POINTS_PER_DECADE = 100


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
    seconds: dict = dataclasses.field(default_factory=dict)

    def as_dict(self) -> dict:
        """JSON-ready copy."""
        return dataclasses.asdict(self)


@dataclasses.dataclass
class RunResult:
    """Everything a run produced.

    Attributes
    ----------
    scene : Scene
    data : dict
        Every number of the report, JSON-ready (see :mod:`spacecraft.report`).
    stats : RunStats
    truth : dict
        ``verdict`` and ``sim`` truth plants (control.StateSpace), ``spacecraft``.
    designs : dict
        Per design variant: ``plant``, ``sim_plant``, ``controllers`` {type: StateSpace},
        ``spacecraft``, ``appendages`` (models per appendage name).
    responses : dict
        ``(variant, controller, "design"|"truth")`` -> control.TimeResponseData.
    loops : dict
        ``(variant, controller, "design"|"truth")`` -> closed-loop StateSpace.
    models : dict
        Per appendage name: ``beam``, ``truth``, ``fits`` {match: HingedChain}.
    exact_frd : control.FrequencyResponseData or None
    """

    scene: Scene
    data: dict
    stats: RunStats
    truth: dict
    designs: dict
    responses: dict
    loops: dict
    models: dict
    exact_frd: object = None


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


class _Runner:
    def __init__(self, scene: Scene, progress: ProgressCallback | None, stats: RunStats,
                 time_responses: bool = True):
        self.time_responses = time_responses
        self.scene = scene
        self.progress = progress or (lambda message: None)
        self.stats = stats
        self._index = {a.name: k for k, a in enumerate(scene.appendages)}
        with self.scene_values("hub"):
            self.hub = Hub(scene.hub.mass, scene.hub.inertia)
        self._cache: dict = {}
        self._modal_spacecraft: set = set()

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
        def build():
            with self.scene_values(self.key(spec, "beam")):
                return spec.beam.build()
        return self.cached(("beam", spec.beam), build)

    def chain(self, spec: AppendageSpec, chain: ChainSpec):
        from appendages.chain import HingedChain

        which = "truth_chain" if chain is spec.truth_chain else "chain"

        def build():
            with self.scene_values(self.key(spec, which)):
                return built()

        def built():
            if chain.from_beam is None:
                return HingedChain(chain.lengths, chain.masses, chain.inertias,
                                   chain.hinge_stiffnesses, hinge_dampings=chain.hinge_dampings,
                                   com_offsets=chain.com_offsets, root=chain.root)
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
        """Chain fitted to the beam, with the beam's modal damping at its first frequency."""
        def build():
            from appendages.chain import HingedChain
            from appendages.equivalence import fit_chain

            beam = self.beam(spec)
            self.stats.chain_fits += 1
            with warnings.catch_warnings(), self.scene_values(
                    self.key(spec, "fit"), f"cannot fit a chain (match = {match!r}): "):
                warnings.simplefilter("ignore", RuntimeWarning)
                chain = fit_chain(beam, spec.fit.n_bodies, match=match)
            zeta = beam.damping_ratio
            if zeta == 0.0:
                return chain
            # hinge damping 2 zeta c / w_1: damping ratio zeta at the chain's first mode, as the
            # beam's modal damping (stiffness-proportional, Rayleigh)
            w1 = float(chain.poles()[0])
            return HingedChain(chain.lengths, chain.masses, chain.inertias,
                               chain.hinge_stiffnesses,
                               hinge_dampings=2.0 * zeta * chain.hinge_stiffnesses / w1,
                               com_offsets=chain.com_offsets, root=chain.root)
        # identical beams (two symmetric wings) share one fit
        return self.cached(("fit", spec.beam, spec.fit.n_bodies, match), build)

    def undamped_beam(self, spec: AppendageSpec):
        """The appendage's beam without damping (for the choice of the number of modes)."""
        from appendages import Beam

        def build():
            beam = self.beam(spec)
            if beam.damping_ratio == 0.0:
                return beam
            return Beam(beam.length, beam.bending_stiffness, beam.linear_density)
        return self.cached(("undamped beam", spec.beam), build)

    def truth_model(self, spec: AppendageSpec, n_modes: int | None):
        if spec.truth == "beam":
            def build():
                with self.scene_values("fidelity"):
                    return self.beam(spec).truncated(n_modes, method=self.scene.fidelity.method)
            return self.cached(("truncated", spec.name, n_modes, self.scene.fidelity.method),
                               build)
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
                    mounts.append(Mount(model, a.position, a.direction, name=a.name))
            return Spacecraft(self.hub, mounts)
        return self.cached(("spacecraft", key), build)

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
            if tip:
                self.stats.tip_deflection_outputs += len(sc.mounts)
            if root_loads:
                self.stats.root_load_outputs += 2 * len(sc.mounts)
            return full, {"modes_total": int(n_total), "modes_kept": int(kept),
                          "modes_dropped": int(n_total - kept)}
        return self.cached(("plant", key, tip, root_loads, disturbances, prune), build)

    # -- exact reference -----------------------------------------------------------------------
    def exact_spacecraft(self) -> Spacecraft:
        models = [self.beam(a) if a.truth == "beam" else self.truth_model(a, None)
                  for a in self.scene.appendages]
        return self.spacecraft("exact", models)

    def exact_frequencies(self, k: int) -> np.ndarray:
        def build():
            self.stats.exact_reference_evaluations += 1
            return self.exact_spacecraft().natural_frequencies(k, exact=True)
        return self.cached(("exact_frequencies", k), build)

    def exact_response(self, omega: np.ndarray) -> np.ndarray:
        self.stats.exact_reference_evaluations += 1
        frd = self.exact_spacecraft().frequency_response(omega, output="theta")
        return np.asarray(frd.frdata).reshape(-1)

    # -- the run -------------------------------------------------------------------------------
    def design_bandwidth(self, inertia: float) -> float:
        """Rigid-body closed-loop natural frequency of the fastest controller [rad/s]."""
        from controllers import natural_frequency_from_bandwidth

        c = self.scene.controller
        values = []
        if c.pd is not None:
            values.append(c.pd.natural_frequency if c.pd.natural_frequency is not None
                          else natural_frequency_from_bandwidth(c.pd.bandwidth, c.pd.damping))
        if c.lqr is not None:
            values.append(self.lqr_frequency(inertia))
        return max(values)

    def lqr_frequency(self, inertia: float) -> float:
        """Rigid-body LQR natural frequency [rad/s], refused outside LQR_FREQUENCY_RANGE."""
        lqr = self.scene.controller.lqr
        # rigid-body LQR poles: w = (q / (r J^2))^(1/4) (Anderson & Moore, sec. 5.2), formed
        # as (q/r)^(1/4) / sqrt(J): no overflow of J^2
        w = (lqr.attitude_weight / lqr.torque_weight) ** 0.25 / math.sqrt(inertia)
        lo, hi = LQR_FREQUENCY_RANGE
        if not lo <= w <= hi:
            raise SceneError(
                f"{self.scene.source}: controller.lqr: the weights give a rigid-body "
                f"closed-loop frequency (attitude_weight / (torque_weight J^2))^(1/4) = {w:.3g} "
                f"rad/s with J = {inertia:.4g} kg m^2, outside [{lo:g}, {hi:g}] rad/s; change "
                "attitude_weight or torque_weight")
        return w

    def choose_fidelity(self) -> tuple[int | None, FidelityChoice | None]:
        scene = self.scene
        if not scene.has_beam_truth:
            return None, None
        if scene.fidelity.n_modes is not None:
            return scene.fidelity.n_modes, None
        with self.stage("choosing the number of modes"):
            inertia = self.exact_spacecraft().inertia
            bandwidth = self.design_bandwidth(inertia)

            # The choice compares undamped models (natural frequencies are undamped, and the
            # low-band gain depends on damping only at second order): trial truncations of
            # undamped beams skip the damping projection, and only the chosen one is built
            # with damping.
            def truncated(n):
                models = [self.undamped_beam(a).truncated(n, method=scene.fidelity.method)
                          if a.truth == "beam" else self.truth_model(a, n)
                          for a in scene.appendages]
                sc = self.spacecraft(("undamped truth", n), models)
                plant, _ = self.plant(sc, ("undamped truth", n), prune=scene.fidelity.prune)
                frequencies = sc.modes()[0][3:]
                return frequencies, plant

            def exact_response(omega):
                self.stats.exact_reference_evaluations += 1
                models = [self.undamped_beam(a) if a.truth == "beam" else
                          self.truth_model(a, None) for a in scene.appendages]
                frd = self.spacecraft("undamped exact", models).frequency_response(omega)
                return np.asarray(frd.frdata).reshape(-1)

            with self.scene_values("fidelity.tolerance"):
                choice = choose_n_modes(truncated, self.exact_frequencies, exact_response,
                                        bandwidth=bandwidth, tolerance=scene.fidelity.tolerance,
                                        bandwidth_factor=scene.fidelity.bandwidth_factor,
                                        method=scene.fidelity.method,
                                        first_zero=self.first_clamped_frequency(),
                                        n_max=self.max_modes())
        return choice.n_modes, choice

    def max_modes(self) -> int:
        """Most modes per beam the search from a tolerance may try: fidelity.MAX_MODES, within
        limits.modes and the loop size limits.states allows."""
        scene = self.scene
        cap = min(MAX_MODES, scene.limits.modes)
        while cap > 1:
            trial = scene.replace(fidelity=dataclasses.replace(scene.fidelity, n_modes=cap))
            if estimate_cost(trial).loop_states <= scene.limits.states:
                break
            cap -= 1
        return cap

    def first_clamped_frequency(self) -> float:
        """Lowest clamped-root frequency of the appendages [rad/s] (first zero of theta/torque)."""
        values = []
        for a in self.scene.appendages:
            if a.truth == "beam":
                values.append(float(self.beam(a).cantilever_frequencies(1)[0]))
        return min(values, default=math.inf)

    def run(self) -> RunResult:
        scene = self.scene
        stats = self.stats
        outputs = scene.outputs
        disturbances = (scene.manoeuvre is not None and scene.manoeuvre.disturbance is not None)
        data: dict = {"title": scene.title, "scene": scene.source}

        with self.stage("building models"):
            if scene.controller.lqr is not None:
                self.lqr_frequency(self.exact_spacecraft().inertia)
            for a in scene.appendages:
                if a.design == "fit":
                    for match in a.fit.match:
                        self.fit(a, match)
        n_modes, choice = self.choose_fidelity()
        data["fidelity"] = {
            "n_modes": n_modes, "method": scene.fidelity.method if n_modes else None,
            "prune": scene.fidelity.prune, "chosen_from_tolerance": choice is not None,
            **({"choice": choice.as_dict()} if choice is not None else {}),
        }

        with self.stage("building plants"):
            truth_models = [self.truth_model(a, n_modes) for a in scene.appendages]
            truth_sc = self.spacecraft(("truth", n_modes), truth_models)
            prune = scene.fidelity.prune
            truth_verdict, truth_info = self.plant(truth_sc, ("truth", n_modes), prune=prune)
            truth_sim, sim_info = self.plant(truth_sc, ("truth", n_modes),
                                             tip=outputs.tip_deflection,
                                             root_loads=outputs.root_loads,
                                             disturbances=disturbances, prune=prune)
            stats.modes_kept = sim_info["modes_kept"]
            stats.modes_dropped = sim_info["modes_dropped"]
            data["truth"] = {
                "models": {a.name: _describe(m) for a, m in zip(scene.appendages, truth_models)},
                "n_states": int(truth_sim.nstates), **sim_info,
                "coupled_frequencies": truth_sc.modes()[0][3:3 + 8].tolist(),
            }
            designs = {}
            for variant in scene.design_variants:
                models = [self.design_model(a, variant, n_modes) for a in scene.appendages]
                sc = self.spacecraft(("design", variant), models)
                needs_tip = (scene.controller.lqr is not None
                             and scene.controller.lqr.deflection_weight is not None)
                design_plant, info = self.plant(sc, ("design", variant), tip=needs_tip,
                                                prune=prune)
                sim_plant, _ = self.plant(sc, ("design", variant), tip=outputs.tip_deflection,
                                          root_loads=outputs.root_loads,
                                          disturbances=disturbances, prune=prune)
                designs[variant] = {"spacecraft": sc, "plant": design_plant,
                                    "sim_plant": sim_plant, "controllers": {},
                                    "appendages": dict(zip([a.name for a in scene.appendages],
                                                           models))}
                data.setdefault("designs", {})[variant] = {
                    "models": {a.name: _describe(m) for a, m in zip(scene.appendages, models)},
                    "n_states": int(sim_plant.nstates), **info,
                    "coupled_frequencies": sc.modes()[0][3:3 + 8].tolist(),
                }

        exact_frd = None
        if outputs.exact_reference:
            with self.stage("exact frequency-domain reference"):
                exact_frd = self.exact_reference_frd()
                data["exact"] = {"coupled_frequencies": self.exact_frequencies(8).tolist(),
                                 "inertia": self.exact_spacecraft().inertia}

        with self.stage("tuning controllers"):
            c = scene.controller
            for variant, d in designs.items():
                for kind in c.types:
                    with self.scene_values(f"controller.{kind}", f"cannot tune on the design "
                                                                 f"model ({variant}): "):
                        if kind == "pd":
                            stats.pd_designs += 1
                            K = controllers.pd(d["plant"], natural_frequency=c.pd.natural_frequency,
                                               bandwidth=c.pd.bandwidth, damping=c.pd.damping,
                                               roll_off=c.pd.roll_off, notch=c.pd.notch,
                                               sample_time=c.sample_time)
                        else:
                            stats.lqr_designs += 1
                            with warnings.catch_warnings():
                                warnings.simplefilter("ignore", RuntimeWarning)
                                K = controllers.lqr(
                                    d["plant"], attitude_weight=c.lqr.attitude_weight,
                                    rate_weight=c.lqr.rate_weight,
                                    torque_weight=c.lqr.torque_weight,
                                    deflection_weight=c.lqr.deflection_weight,
                                    estimator_speed=c.lqr.estimator_speed,
                                    sample_time=c.sample_time)
                    if K.dt is None:
                        # a static-gain StateSpace gets dt=None from python-control; it is a
                        # continuous-time controller
                        K = control.ss(K.A, K.B, K.C, K.D, 0, inputs=list(K.input_labels),
                                       outputs=list(K.output_labels), name=K.name)
                    d["controllers"][kind] = K

        responses, loops, rows = {}, {}, []
        with self.stage("closing the loops"):
            for variant, d in designs.items():
                for kind, K in d["controllers"].items():
                    row = {"design": variant, "controller": kind}
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", RuntimeWarning)
                        design_margins = controllers.margins(d["plant"], K)
                        verdict = controllers.spillover(truth_verdict, K)
                    row["design_margins"] = design_margins.as_dict()
                    row["verdict"] = _verdict(verdict)
                    if exact_frd is not None:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore", RuntimeWarning)
                            try:
                                row["exact_verdict"] = _verdict(controllers.spillover(exact_frd, K))
                            except ValueError as exc:
                                row["exact_verdict"] = {"error": str(exc)}
                    if scene.manoeuvre is not None and self.time_responses:
                        for which, plant in (("design", d["sim_plant"]), ("truth", truth_sim)):
                            loop = controllers.close_loop(plant, K)
                            loops[(variant, kind, which)] = loop
                            responses[(variant, kind, which)] = self.simulate(loop)
                        pair = {w: responses[(variant, kind, w)] for w in ("design", "truth")}
                        row["metrics"] = {w: _metrics(r) for w, r in pair.items()}
                        row["diverged"] = {w: diverged_at(r) for w, r in pair.items()}
                        diverging = any(t is not None for t in row["diverged"].values())
                        diff = {}
                        for name in pair["design"].output_labels:
                            a, b = _trace(pair["truth"], name), _trace(pair["design"], name)
                            if a is not None and b is not None:
                                diff[name] = (math.inf if diverging
                                              else float(np.max(np.abs(a - b))))
                        row["peak_difference"] = diff
                    else:
                        loops[(variant, kind, "truth")] = controllers.close_loop(truth_sim, K)
                    rows.append(row)
        data["closed_loops"] = rows

        models = {}
        for a in scene.appendages:
            entry = {"truth": truth_models[scene.appendages.index(a)]}
            if a.beam is not None:
                entry["beam"] = self.beam(a)
            if a.design == "fit":
                entry["fits"] = {m: self.fit(a, m) for m in a.fit.match}
            models[a.name] = entry
        if (scene.report.equivalence and self.time_responses
                and any(a.design == "fit" for a in scene.appendages)):
            with self.stage("equivalence tables"):
                data["equivalence"] = self.equivalence_tables(models)

        data["stats"] = stats.as_dict()
        truth = {"spacecraft": truth_sc, "verdict": truth_verdict, "sim": truth_sim}
        return RunResult(scene, data, stats, truth, designs, responses, loops, models, exact_frd)

    def simulate(self, loop) -> control.TimeResponseData:
        """The manoeuvre's response of a closed loop (outputs only, no state trajectory).

        A loop whose response leaves the float64 range is a result, not an error: the response
        stops at the last sample that could be computed, with the attributes ``diverged``
        (True) and ``diverged_at`` [s] (see :func:`diverged_at`).
        """
        m = self.scene.manoeuvre
        n = int(math.floor(m.duration / m.step + 1e-9)) + 1
        T = np.arange(n) * m.step
        U = np.zeros((loop.ninputs, n))
        labels = list(loop.input_labels)
        U[labels.index("theta_ref")] = controllers.slew_profile(T, m.slew_angle, m.slew_time)
        if m.disturbance is not None:
            d = m.disturbance
            end = math.inf if d.length is None else d.start + d.length
            U[labels.index(d.input)] = np.where((T >= d.start) & (T < end), d.amplitude, 0.0)
        self.stats.simulations += 1
        if loop.isdtime(strict=True):
            with np.errstate(over="ignore", invalid="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                response = control.forced_response(loop, T, U, squeeze=False)
            Y = np.asarray(response.y).reshape(loop.noutputs, -1)
        else:
            self.stats.simulator_setups += 1
            with self.scene_values("manoeuvre.step"):
                simulator = controllers.Simulator(loop, m.step)
            Y = _outputs_until_overflow(simulator, T, U)
        # the response ends before its first sample outside the float range
        finite = np.all(np.isfinite(Y), axis=0)
        k = Y.shape[1] if finite.all() else int(np.argmin(finite))
        k = max(k, 1)
        out = control.TimeResponseData(
            T[:k], Y[:, :k], None, U[:, :k], issiso=loop.issiso(),
            output_labels=list(loop.output_labels), input_labels=list(loop.input_labels),
            sysname=loop.name, title="Manoeuvre of " + loop.name, trace_types=["forced"],
            plot_inputs=True, squeeze=False)
        out.diverged = k < n
        out.diverged_at = float(T[k - 1]) if k < n else None
        return out

    def exact_reference_frd(self):
        """Exact theta and omega per torque of hub + distributed beams, as an FRD."""
        scene = self.scene
        inertia = self.exact_spacecraft().inertia
        wb = self.design_bandwidth(inertia)
        w_lo, w_hi = wb * 1e-3, wb * 1e3
        frequencies = self.exact_frequencies(8)
        while frequencies[-1] < w_hi and frequencies.size < 64:
            frequencies = self.exact_frequencies(2 * frequencies.size)
        n_dec = math.log10(w_hi / w_lo)
        grid = [np.geomspace(w_lo, w_hi, int(_POINTS_PER_DECADE * n_dec))]
        zeta = max([a.beam.damping_ratio for a in scene.appendages if a.beam is not None]
                   + [1e-4])
        # an even count: no point exactly at a mode (an undamped beam's W is infinite there)
        spread = np.tan(np.linspace(-1.5, 1.5, 60))
        for f in frequencies[frequencies < w_hi]:
            grid.append(f * (1.0 + max(zeta, 1e-4) * spread))
        omega = np.unique(np.concatenate(grid))
        omega = omega[(omega > 0) & (omega <= w_hi)]
        theta = self.exact_response(omega)
        data = np.stack([theta, 1j * omega * theta]).reshape(2, 1, -1)
        return control.frd(data, omega, inputs=["torque"], outputs=["theta", "omega"])

    def equivalence_tables(self, models) -> list:
        """Paper's table per fitted beam: exact beam, 2-mode beam, each fitted chain."""
        tables = []
        done = set()
        for a in self.scene.appendages:
            if a.design != "fit":
                continue
            key = (a.beam, a.fit.n_bodies, a.fit.match)
            if key in done:
                continue
            done.add(key)
            fits = {m: models[a.name]["fits"][m] for m in a.fit.match}
            table = equivalence_table(self.beam(a), fits, stats=self.stats)
            table["appendage"] = a.name
            tables.append(table)
        return tables


#: Column labels of the fitted chains in the equivalence table.
FIT_LABELS = {"poles-and-zeros": "chain, flexsat fit", "frequencies": "chain, paper's fit",
              "design": "design model"}


def equivalence_table(beam, fits: dict, *, stats: RunStats | None = None) -> dict:
    """The paper's equivalence table against the exact beam, JSON-ready.

    Parameters
    ----------
    beam : appendages.Beam
        The distributed beam (reference: its exact W, poles and zeros).
    fits : dict
        ``match -> HingedChain`` (keys of :data:`FIT_LABELS`) or ``label -> model``.
    stats : RunStats, optional
        Counts one exact-reference evaluation per column.

    Returns
    -------
    dict
        ``quantities``, ``units``, ``exact`` (the exact beam's values, None where not defined)
        and ``columns``: for the paper's 2-mode free-free beam and each chain, ``name``,
        ``values``, ``relative_error`` against the exact beam and ``max_log_error`` of
        W1..W4 over the band (see :func:`appendages.equivalence.criterion`).
    """
    from appendages.equivalence import criterion

    candidates = [("beam, 2 modes (paper)", beam.truncated(2, method="free-free"))]
    candidates += [(FIT_LABELS.get(k, k), model) for k, model in fits.items()]
    columns, reference, units = [], None, None
    for label, model in candidates:
        if stats is not None:
            stats.exact_reference_evaluations += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            result = criterion(beam, model, names=("beam (exact)", label))
        rows = result.rows()
        if reference is None:
            reference = [r[2] for r in rows]
            units = [(r[0], r[1]) for r in rows]
        column = {"name": label, "values": [r[3] for r in rows],
                  "relative_error": [r[4] for r in rows],
                  "max_log_error": result.max_log_error.tolist(), "band": list(result.band)}
        if hasattr(model, "hinge_stiffnesses"):
            column["parameters"] = _describe(model)
        columns.append(column)
    return {"quantities": [u[0] for u in units], "units": [u[1] for u in units],
            "exact": reference, "columns": columns}


def _outputs_until_overflow(simulator, T: np.ndarray, U: np.ndarray) -> np.ndarray:
    """Outputs on ``T``; where the response overflows float64, those of the longest prefix of
    ``T`` that does not (found by bisection; the simulator's set-up is reused), padded with inf.

    ``controllers.Simulator`` raises FloatingPointError when an unstable loop's response leaves
    the float64 range; the prefix shows how it diverged up to then.
    """
    n = T.size
    try:
        return simulator.outputs(T, U)
    except FloatingPointError:
        pass
    good, bad, Y = 1, n, None       # prefixes of `good` samples compute, of `bad` overflow
    while bad - good > 1:
        mid = (good + bad) // 2
        try:
            Y = simulator.outputs(T[:mid], U[:, :mid])
            good = mid
        except FloatingPointError:
            bad = mid
    out = np.full((simulator.n_outputs, n), np.inf)
    if good >= 2:
        out[:, :good] = Y if Y is not None and Y.shape[1] == good else \
            simulator.outputs(T[:good], U[:, :good])
    else:
        # X0 = 0: the first output is the feedthrough
        D = np.asarray(simulator.system.D, dtype=float)
        out[:, 0] = D @ U[:, 0]
    return out


def diverged_at(response) -> float | None:
    """Time [s] at which a response's simulation stopped because it diverged, or None.

    Reads the attributes ``diverged`` and ``diverged_at`` that :meth:`_Runner.simulate` (and
    controllers' responses, where they provide them) set; a response without them diverged if
    it has a non-finite output sample (at the last finite sample before it).
    """
    if hasattr(response, "diverged"):
        if not response.diverged:
            return None
        at = getattr(response, "diverged_at", None)
        return float(at) if at is not None else float(np.asarray(response.t).reshape(-1)[-1])
    y = np.asarray(response.y)
    y = y.reshape(-1, y.shape[-1])
    finite = np.all(np.isfinite(y), axis=0)
    if finite.all():
        return None
    k = int(np.argmin(finite))
    t = np.asarray(response.t).reshape(-1)
    return float(t[max(k - 1, 0)])


def _metrics(response) -> dict:
    """controllers.metrics, every metric +inf for a response that diverged (its convention)."""
    with np.errstate(over="ignore", invalid="ignore"):
        values = controllers.metrics(response)
    if diverged_at(response) is not None:
        values = {name: math.inf for name in values}
    return values


def _trace(response, name):
    labels = list(response.output_labels)
    if name not in labels:
        return None
    return np.asarray(response.y).reshape(len(labels), -1)[labels.index(name)]


def _verdict(v) -> dict:
    return {"stable": bool(v.stable), "n_unstable_poles": int(v.n_unstable_poles),
            "least_damping_ratio": v.least_damping_ratio,
            "least_damped_frequency": v.least_damped_frequency,
            "method": v.method, **v.margins.as_dict(),
            "gain_crossover_frequency": v.margins.gain_crossover_frequency}


def _describe(model) -> dict:
    """Parameters of an appendage model, JSON-ready."""
    out = {"type": type(model).__name__, "length": float(model.length),
           "mass": float(model.mass), "inertia": float(model.inertia)}
    if hasattr(model, "lengths"):
        out.update(root=model.root, lengths=model.lengths.tolist(), masses=model.masses.tolist(),
                   inertias=model.inertias.tolist(),
                   hinge_stiffnesses=model.hinge_stiffnesses.tolist(),
                   hinge_dampings=(None if model.hinge_dampings is None
                                   else np.asarray(model.hinge_dampings).tolist()),
                   com_offsets=model.com_offsets.tolist())
    if hasattr(model, "n_modes"):
        out.update(n_modes=int(model.n_modes), method=getattr(model, "method", None))
    if hasattr(model, "poles"):
        try:
            out["natural_frequencies"] = np.asarray(model.poles())[:6].tolist()
        except ValueError:
            pass
    return out


def run(scene=None, *, progress: ProgressCallback | None = None,
        stats: RunStats | None = None, time_responses: bool = True) -> RunResult:
    """Run a scene: build the models it needs, tune, close the loops, collect the numbers.

    Parameters
    ----------
    scene : Scene, path, dict or None
        Anything :func:`~spacecraft.scene.load_scene` accepts (None: the default scene).
    progress : callable, optional
        Called with a short message at the start of each stage.
    stats : RunStats, optional
        Counters to add to (a new one by default).
    time_responses : bool
        Simulate the manoeuvre (False: only tune and close the loops, e.g. for FMU export).

    Returns
    -------
    RunResult
        Files (report, plots, FMUs) are written by :func:`spacecraft.report.write_report`.

    Raises
    ------
    SceneError
        Invalid scene, or a controller that cannot be tuned on the design model.
    """
    scene = load_scene(scene)
    stats = RunStats() if stats is None else stats
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        result = _Runner(scene, progress, stats, time_responses).run()
    result.data["warnings"] = warning_lines(caught)
    return result


def warning_lines(caught) -> list[str]:
    """Distinct warnings as one line each (``Category: message (module:line)``), at most 20,
    each at most about 300 characters: what the report and the command line show instead of
    numpy's or scipy's multi-line output."""
    seen: dict = {}
    for w in caught:
        message = " ".join(str(w.message).split())
        if len(message) > 250:
            message = message[:250] + "..."
        key = (w.category.__name__, message)
        seen.setdefault(key, f"{Path(w.filename).name}:{w.lineno}")
    lines = [f"{category}: {message} ({where})"
             for (category, message), where in list(seen.items())[:_MAX_WARNINGS]]
    if len(seen) > _MAX_WARNINGS:
        lines.append(f"... and {len(seen) - _MAX_WARNINGS} more distinct warnings")
    return lines
