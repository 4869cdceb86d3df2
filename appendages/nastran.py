r"""NASTRAN modal solutions (SOL 103) as modal appendages, read through pyNastran.

A structures team runs the appendage's finite-element model with its attachment point (the
*root* grid) clamped (``SPC 123456`` there) in a normal-modes solution and hands over the OP2
file. :func:`read_nastran` turns it into a :class:`~appendages.ModalAppendage`:

* the cantilever frequencies from the eigenvalue table (LAMA) or the eigenvectors' headers;
* the participation factors ``G = Phi^T M D`` of the mass-normalised modes at the root, from
  (1) the eigenvectors and the model's mass matrix (``mass_matrix=``: M over the eigenvectors'
  degrees of freedom, as the solution used it, WTMASS included), or (2) the modal participation
  factors of ``MEFFMASS(PLOT)`` (MPFACS, per unit generalized mass:
  ``G_i = Gamma_i sqrt(m_i)``), or (3) the single-point constraint forces of each mode at the
  root (``SPCFORCES``): the root holds the clamped structure vibrating in mode i, so
  ``K Phi_i = w_i**2 M Phi_i + R_i`` with R_i the reaction; ``D^T K = 0`` (a rigid motion has
  no strain energy) gives ``D^T R_i = -w_i**2 D^T M Phi_i``, i.e. ``G_i = -r_i/w_i**2`` with r_i
  the reaction at the root about the root point;
* the rigid mass about the root ``D^T M D``, from the mass matrix or from the grid point
  weight generator (``PARAM,GRDPNT``; OGPWG: about its reference point, moved to the root),
  times WTMASS (the GPWG prints weight units when ``PARAM,WTMASS`` is set).

D is the rigid motion of every grid for a unit motion of the root, in the basic system. The
data are then turned into the appendage's axes (``axes``: columns the appendage's x, y, z in
the basic system; x along the appendage) and into SI (``units``: NASTRAN has none).

What is refused, by name: a file without a normal-modes solution (the tables found are
listed); eigenvectors of another analysis (buckling); rigid-body modes (a model not held at
the root); a root grid that moves in some mode (not clamped: a pinned root is not a cantilever
interface); grids held besides the root (a model clamped elsewhere, whose modes are not the
appendage's on a free hub) unless the mass matrix shows they carry no mass (an unconnected
grid); output coordinate systems other than the basic one; a mass matrix that does not give
the file's generalized masses or rigid mass.

pyNastran is an optional dependency (``pip install "flexsat[nastran]"``). Its extraction is
kept apart (:func:`read_op2` -> :class:`NastranModes`), and a :class:`NastranModes` can be
saved to and loaded from a NumPy ``.npz`` file (:meth:`NastranModes.save`,
:meth:`NastranModes.load`): the conversion itself needs numpy only.

References
----------
.. [1] MSC Nastran Quick Reference Guide: SPC, PARAM GRDPNT, WTMASS, MEFFMASS, EIGRL (NORM).
.. [2] MSC Nastran Dynamic Analysis User's Guide, ch. 3 (normal modes, modal effective mass).
.. [3] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., 2006,
   ch. 17 (constraint modes and fixed-interface modes).
.. [4] S. Doyle, pyNastran, https://github.com/SteveDoyle2/pyNastran (BSD 3-clause).
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings

import numpy as np

from .errors import FlexsatError, describe
from .modal_data import ModalAppendage
from .units import LENGTH_UNITS, MASS_UNITS, modal_data_to_si, unit_factor

__all__ = ["NastranError", "NastranModes", "modal_appendage", "read_nastran", "read_op2"]

_COMPONENTS = ("T1", "T2", "T3", "R1", "R2", "R3")
_NPZ_FORMAT = "flexsat-nastran-modes-1"
# Relative tolerances of the consistency checks: OP2 results are single precision (7 digits).
_GENERALIZED_MASS_RTOL = 1e-4
_RIGID_MASS_RTOL = 1e-4
# A component of a mode shape below this fraction of the mode's largest is taken as zero
# (constrained degrees of freedom are printed as exact zeros).
_HELD_RTOL = 1e-9


class NastranError(FlexsatError, ValueError):
    """A NASTRAN file that does not hold what a modal appendage needs (the message says what)."""


@dataclasses.dataclass(frozen=True, eq=False)
class NastranModes:
    """What a normal-modes solution holds for a modal appendage, as plain arrays (model units).

    Attributes
    ----------
    source : str
        The file it came from.
    node_ids : ndarray of int, (N,)
        Grid ids, in the eigenvectors' order.
    frequencies : ndarray, (n,)
        Natural frequencies [rad per model time unit, i.e. rad/s].
    eigenvectors : ndarray, (n, N, 6)
        Mode shapes at the grids, components T1, T2, T3, R1, R2, R3 in each grid's output
        system, as the solver normalised them.
    generalized_masses : ndarray (n,) or None
        ``Phi_i^T M Phi_i`` of the modes as given (LAMA), None when the file has no
        eigenvalue table.
    positions : ndarray (N, 3) or None
        Grid positions in the basic system (BGPDT), None without geometry tables.
    output_systems : ndarray of int (N,) or None
        Each grid's displacement output coordinate system (CD; 0 = basic).
    spc_node_ids : ndarray of int (K,) or None
    spc_forces : ndarray (n, K, 6) or None
        Single-point constraint forces of each mode at those grids (output systems).
    gpwg_reference : int or None
        The grid point weight generator's reference point (0: the basic origin; else a grid).
    gpwg_mass : ndarray (6, 6) or None
        Its rigid mass matrix MO about that point, basic system, as printed (weight units if
        WTMASS != 1).
    participation_factors : ndarray (n, 6) or None
        MEFFMASS's modal participation factors (MPFACS), per unit generalized mass, about the
        GPWG reference point, basic system.
    rigid_body_mass : ndarray (6, 6) or None
        MEFFMASS's rigid body mass matrix (RBMASS).
    wtmass : float
        PARAM,WTMASS (1 when absent).
    analysis_code : int
        Of the eigenvectors: 2 for real eigenvalues (normal modes).
    """

    source: str
    node_ids: np.ndarray
    frequencies: np.ndarray
    eigenvectors: np.ndarray
    generalized_masses: np.ndarray | None = None
    positions: np.ndarray | None = None
    output_systems: np.ndarray | None = None
    spc_node_ids: np.ndarray | None = None
    spc_forces: np.ndarray | None = None
    gpwg_reference: int | None = None
    gpwg_mass: np.ndarray | None = None
    participation_factors: np.ndarray | None = None
    rigid_body_mass: np.ndarray | None = None
    wtmass: float = 1.0
    analysis_code: int = 2

    _ARRAYS = ("node_ids", "frequencies", "eigenvectors", "generalized_masses", "positions",
               "output_systems", "spc_node_ids", "spc_forces", "gpwg_mass",
               "participation_factors", "rigid_body_mass")

    def save(self, path) -> None:
        """Save to a NumPy ``.npz`` file (absent items are left out)."""
        arrays = {name: getattr(self, name) for name in self._ARRAYS
                  if getattr(self, name) is not None}
        scalars = {"format": np.array(_NPZ_FORMAT), "source": np.array(self.source),
                   "wtmass": np.array(self.wtmass), "analysis_code": np.array(self.analysis_code)}
        if self.gpwg_reference is not None:
            scalars["gpwg_reference"] = np.array(self.gpwg_reference)
        np.savez(os.fspath(path), **arrays, **scalars)

    @classmethod
    def load(cls, path) -> "NastranModes":
        """Load what :meth:`save` wrote.

        Raises
        ------
        NastranError
            Not such a file, or one without modes.
        """
        name = os.fspath(path)
        try:
            with np.load(name, allow_pickle=False) as data:
                items = {key: data[key] for key in data.files}
        except (OSError, ValueError) as exc:
            raise NastranError(f"{name}: not a NumPy .npz file ({exc})") from None
        if items.get("format") is None or str(items["format"]) != _NPZ_FORMAT:
            raise NastranError(f"{name}: not a flexsat NASTRAN-modes file (format "
                               f"{_NPZ_FORMAT!r} expected)")
        missing = [k for k in ("node_ids", "frequencies", "eigenvectors") if k not in items]
        if missing:
            raise NastranError(f"{name}: no modal solution (missing {missing})")
        kwargs = {k: items[k] for k in cls._ARRAYS if k in items}
        return cls(source=str(items["source"]), wtmass=float(items["wtmass"]),
                   analysis_code=int(items["analysis_code"]),
                   gpwg_reference=(int(items["gpwg_reference"]) if "gpwg_reference" in items
                                   else None), **kwargs)


# ---------------------------------------------------------------------------------------------
# extraction through pyNastran
# ---------------------------------------------------------------------------------------------
def _import_read_op2():
    try:
        from pyNastran.op2.op2 import read_op2 as pynastran_read_op2
    except Exception as exc:  # ImportError, or an old pyNastran failing on a new numpy
        raise ImportError(
            "reading NASTRAN OP2 files needs pyNastran (pip install \"flexsat[nastran]\"), "
            f"which did not import: {type(exc).__name__}: {exc}") from None
    return pynastran_read_op2


def _one(mapping: dict, what: str, subcase, name: str):
    """The entry of ``mapping`` for ``subcase`` (or the only one)."""
    if subcase is not None:
        if subcase not in mapping:
            raise NastranError(f"{name}: no {what} for subcase {subcase!r}; the file has "
                               f"{sorted(mapping, key=str)}")
        return mapping[subcase]
    if len(mapping) > 1:
        raise NastranError(f"{name}: {what} of several subcases {sorted(mapping, key=str)}: "
                           "give subcase=")
    return next(iter(mapping.values()))


def _grid_geometry(model, node_ids: np.ndarray):
    """(positions (N, 3) basic, output systems (N,)) of the grids, or (None, None)."""
    results = getattr(model, "op2_results", None)
    bgpdt = getattr(results, "bgpdt", None)
    eqexin = getattr(results, "eqexin", None)
    if bgpdt is None or eqexin is None:
        return None, None
    internal = np.asarray(eqexin.nid)[np.argsort(np.asarray(eqexin.dof), kind="stable")]
    xyz = np.asarray(bgpdt.xyz, dtype=float)
    cd = np.asarray(bgpdt.nid_cp_cd_ps)  # pyNastran keeps BGPDT's CD column under this name
    cd = cd[:, -1] if cd.ndim == 2 and cd.shape[1] == 1 else cd.reshape(xyz.shape[0], -1)[:, 0]
    if internal.size != xyz.shape[0]:
        return None, None
    row = {int(nid): k for k, nid in enumerate(internal)}
    try:
        index = np.array([row[int(nid)] for nid in node_ids])
    except KeyError:
        return None, None
    return xyz[index], cd[index].astype(int)


def _param(model, name: str, default: float) -> float:
    param = getattr(model, "params", {}).get(name)
    if param is None:
        return default
    values = getattr(param, "values", None) or [getattr(param, "value", default)]
    return float(values[0])


def read_op2(path, *, subcase=None) -> NastranModes:
    """Extract a normal-modes solution from an OP2 file with pyNastran.

    Parameters
    ----------
    path : str or os.PathLike
    subcase : int, optional
        Which subcase's modes, when the file has several.

    Raises
    ------
    ImportError
        pyNastran is missing or fails to import.
    NastranError
        The file is not readable as OP2, or holds no normal-modes solution (the message lists
        the result tables it has).
    """
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise FileNotFoundError(f"{name}: no such file")
    pynastran_read_op2 = _import_read_op2()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = pynastran_read_op2(name, debug=None, log=None, build_dataframe=False,
                                       mode=None)
    except Exception as exc:
        raise NastranError(f"{name}: not readable as a NASTRAN OP2 file "
                           f"({type(exc).__name__}: {exc})") from None
    vectors = getattr(model, "eigenvectors", {}) or {}
    if not vectors:
        found = [t for t in model.get_table_types() if _non_empty(model, t)]
        raise NastranError(
            f"{name}: no modal solution (no eigenvectors of a normal-modes solution, SOL 103 "
            f"with DISPLACEMENT output); the file holds {found or 'no results'}")
    vec = _one(vectors, "eigenvectors", subcase, name)
    node_ids = np.asarray(vec.node_gridtype[:, 0], dtype=np.int64)
    grid_types = np.asarray(vec.node_gridtype[:, 1])
    if np.any(grid_types != 1):
        bad = node_ids[grid_types != 1]
        raise NastranError(f"{name}: the modes have scalar or extra points {describe(bad.tolist())}:"
                           f" only grids (six components each) are supported")
    eigenvalues = getattr(model, "eigenvalues", {}) or {}
    generalized = None
    if eigenvalues:
        lama = (_one(eigenvalues, "eigenvalue tables", None, name) if len(eigenvalues) == 1
                else None)
        if lama is not None and hasattr(lama, "radians") and len(lama.radians) >= \
                vec.data.shape[0]:
            frequencies = np.asarray(lama.radians, dtype=float)[:vec.data.shape[0]]
            generalized = np.asarray(lama.generalized_mass, dtype=float)[:vec.data.shape[0]]
    if generalized is None:
        lam = np.asarray(getattr(vec, "eigns", np.full(vec.data.shape[0], np.nan)), dtype=float)
        frequencies = np.sqrt(np.where(lam >= 0, lam, np.nan))
    positions, systems = _grid_geometry(model, node_ids)
    spc_ids = spc = None
    spc_tables = getattr(model, "spc_forces", {}) or {}
    if spc_tables:
        table = _one(spc_tables, "SPC forces", subcase, name)
        if getattr(table, "analysis_code", None) == vec.analysis_code and \
                table.data.shape[0] == vec.data.shape[0]:
            spc_ids = np.asarray(table.node_gridtype[:, 0], dtype=np.int64)
            spc = np.asarray(table.data, dtype=float)
    gpwg_reference = gpwg_mass = None
    gpwg = getattr(model, "grid_point_weight", {}) or {}
    if gpwg:
        weight = next(iter(gpwg.values()))
        gpwg_reference = int(weight.reference_point)
        gpwg_mass = np.asarray(weight.MO, dtype=float)
    matrices = getattr(model, "matrices", {}) or {}
    participation = rigid_body = None
    if "MPFACS" in matrices:
        participation = _matrix_rows(matrices["MPFACS"], vec.data.shape[0], name, "MPFACS")
    if "RBMASS" in matrices:
        rigid_body = np.asarray(_dense(matrices["RBMASS"]), dtype=float).reshape(6, 6)
    return NastranModes(
        source=name, node_ids=node_ids, frequencies=frequencies,
        eigenvectors=np.asarray(vec.data, dtype=float), generalized_masses=generalized,
        positions=positions, output_systems=systems, spc_node_ids=spc_ids, spc_forces=spc,
        gpwg_reference=gpwg_reference, gpwg_mass=gpwg_mass,
        participation_factors=participation, rigid_body_mass=rigid_body,
        wtmass=_param(model, "WTMASS", 1.0), analysis_code=int(vec.analysis_code))


def _non_empty(model, table: str) -> bool:
    obj = model
    for part in table.split("."):
        obj = getattr(obj, part, None)
    return bool(obj) if isinstance(obj, dict) else obj is not None


def _dense(matrix) -> np.ndarray:
    data = getattr(matrix, "data", matrix)
    return data.toarray() if hasattr(data, "toarray") else np.asarray(data)


def _matrix_rows(matrix, n_modes: int, name: str, label: str) -> np.ndarray:
    """A 6 x n (or n x 6) MEFFMASS matrix as (n, 6) rows per mode."""
    data = np.asarray(_dense(matrix), dtype=float)
    if data.shape == (6, n_modes):
        return data.T.copy()
    if data.shape == (n_modes, 6):
        return data.copy()
    raise NastranError(f"{name}: {label} has shape {data.shape}; expected 6 x {n_modes} (one "
                       f"column per mode)")


# ---------------------------------------------------------------------------------------------
# conversion
# ---------------------------------------------------------------------------------------------
def _rigid_motion(offset: np.ndarray) -> np.ndarray:
    """6x6 map from (u, theta) at a point to the motion of a point at ``offset`` from it."""
    T = np.eye(6)
    x, y, z = offset
    T[:3, 3:] = -np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])  # u + theta x offset
    return T


def _check_axes(axes) -> np.ndarray:
    if axes is None:
        return np.eye(3)
    A = np.asarray(axes, dtype=float)
    if A.shape != (3, 3) or not np.all(np.isfinite(A)) or \
            np.max(np.abs(A.T @ A - np.eye(3))) > 1e-9 or np.linalg.det(A) < 0:
        raise ValueError(f"axes must be a 3x3 rotation (columns: the appendage's x, y, z in the "
                         f"basic system; R^T R = I to 1e-9, det +1); got {describe(axes)}")
    return A


def _check_units(units, name: str) -> tuple[float, float]:
    if isinstance(units, dict):
        unknown = sorted(set(units) - {"length", "mass"})
        if unknown or set(units) != {"length", "mass"}:
            raise ValueError(f"units must give 'length' and 'mass' (NASTRAN has no units); "
                             f"got {describe(units)}")
        units = (units["length"], units["mass"])
    if isinstance(units, str) or not isinstance(units, (tuple, list)) or len(units) != 2:
        raise TypeError(f"units must be (length, mass), e.g. ('m', 'kg') or ('in', 'slinch'), "
                        f"names from {list(LENGTH_UNITS)} and {list(MASS_UNITS)}; got "
                        f"{describe(units)}")
    return unit_factor("length", units[0], "units: "), unit_factor("mass", units[1], "units: ")


def modal_appendage(modes: NastranModes, *, root: int, units, axes=None, mass_matrix=None,
                    damping=0.0, length: float | None = None, tip: int | None = None,
                    n_modes: int | None = None) -> ModalAppendage:
    """A :class:`~appendages.ModalAppendage` from a NASTRAN normal-modes solution.

    Parameters
    ----------
    modes : NastranModes
        From :func:`read_op2` or :meth:`NastranModes.load`.
    root : int
        The grid where the appendage attaches: clamped (all six components) in the solution.
    units : (str, str) or dict
        The model's length and mass units, e.g. ``("m", "kg")``, ``("mm", "t")``,
        ``("in", "slinch")`` (:data:`~appendages.units.LENGTH_UNITS`,
        :data:`~appendages.units.MASS_UNITS`); time in seconds.
    axes : (3, 3) array, optional
        The appendage's x, y, z axes (columns) in the basic system; x along the appendage from
        the root. Default: the basic axes.
    mass_matrix : (6N, 6N) array or scipy.sparse matrix, optional
        The mass matrix of the solution (WTMASS included) over the eigenvectors' degrees of
        freedom (grid by grid in :attr:`NastranModes.node_ids` order, components T1..R3 in
        the basic system). Gives the participation and the rigid mass, checked against the
        file's generalized masses and GPWG.
    damping : float or array_like
        Modal damping ratios of the cantilever modes [-] (a normal-modes solution has none).
    length : float, optional
        Extent along the appendage's x axis [model length unit]; default the farthest grid
        (carrying mass, when the mass matrix is given) from the root along x.
    tip : int, optional
        A grid whose motion gives the modes' tip motion (deflections along the appendage's
        y and z, twist about x).
    n_modes : int, optional
        Keep the first n_modes modes.

    Returns
    -------
    ModalAppendage
        Three-axis, SI, in the appendage's axes (``planar_view()`` for the x-y plane).

    Raises
    ------
    NastranError
        What the module docstring lists, naming the file, the grid and the mode.
    """
    name = modes.source
    length_unit, mass_unit = _check_units(units, name)
    A = _check_axes(axes)
    phi = np.asarray(modes.eigenvectors, dtype=float)
    n_all, n_grids = phi.shape[:2]
    if modes.analysis_code != 2:
        raise NastranError(f"{name}: the eigenvectors are not of a normal-modes solution "
                           f"(analysis code {modes.analysis_code}; 2 expected: SOL 103, not a "
                           f"buckling or complex-modes solution)")
    w = np.asarray(modes.frequencies, dtype=float)
    if w.shape != (n_all,) or not np.all(np.isfinite(w)) or np.any(w <= 0.0):
        bad = int(np.flatnonzero(~(np.isfinite(w) & (w > 0.0)))[0]) if w.shape == (n_all,) \
            else -1
        raise NastranError(
            f"{name}: mode {bad + 1} has the frequency {w[bad] if bad >= 0 else w!r}: rigid-body "
            f"modes mean the model is not held at the root (a free-free solution); a modal "
            f"appendage needs the modes with its root grid clamped (SPC 123456)")
    if n_modes is not None:
        if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or \
                not 1 <= n_modes <= n_all:
            raise ValueError(f"n_modes must be an integer from 1 to {n_all} (the file's modes);"
                             f" got {describe(n_modes)}")
    keep = n_all if n_modes is None else int(n_modes)
    ids = np.asarray(modes.node_ids)
    where = {int(g): k for k, g in enumerate(ids)}
    if isinstance(root, bool) or not isinstance(root, (int, np.integer)) or int(root) not in where:
        raise NastranError(f"{name}: root must be a grid id of the modes; got {describe(root)} "
                           f"(grids {describe(ids.tolist())})")
    if modes.output_systems is not None and np.any(np.asarray(modes.output_systems) != 0):
        bad = ids[np.asarray(modes.output_systems) != 0]
        raise NastranError(f"{name}: grids {describe(bad.tolist())} give their motion in "
                           f"another coordinate system than the basic one (CD != 0): set their "
                           f"CD to 0 or PARAM,OUGCORD,BASIC")
    k_root = where[int(root)]
    scale = np.max(np.abs(phi), axis=(1, 2))
    held = np.abs(phi) <= _HELD_RTOL * scale[:, None, None]
    moving = ~held[:, k_root, :]
    if np.any(moving):
        mode, comp = (int(v) for v in np.argwhere(moving)[0])
        raise NastranError(
            f"{name}: the root grid {root} moves in mode {mode + 1} (component "
            f"{_COMPONENTS[comp]} = {phi[mode, k_root, comp]:.4g}): the solution is not clamped "
            f"there; the constrained root must be the interface, held in all six components "
            f"(SPC 123456) and nowhere else")
    M_full = None
    if mass_matrix is not None:
        M_full = _check_mass_matrix(mass_matrix, 6 * n_grids, name)
    others = [k for k in range(n_grids) if k != k_root and np.all(held[:, k, :])]
    if others:
        carrying = others
        if M_full is not None:
            diag = np.asarray(M_full.diagonal()).reshape(n_grids, 6)
            carrying = [k for k in others if np.any(diag[k] > 0.0)]
        if carrying:
            raise NastranError(
                f"{name}: the modes hold grid(s) {describe([int(ids[k]) for k in carrying])} "
                f"fixed besides the root grid {root}: the constrained root must be the "
                f"interface alone (a model clamped elsewhere has other modes than the appendage "
                f"on a free hub)" + ("" if M_full is not None else
                                     "; if they carry no mass (unconnected grids), give "
                                     "mass_matrix= so that this can be checked"))
    if modes.positions is None:
        raise NastranError(f"{name}: no grid positions (BGPDT) in the file: write the OP2 with "
                           "PARAM,POST,-1 or -2 (geometry tables)")
    r = np.asarray(modes.positions, dtype=float)
    r0 = r[k_root]
    D = np.concatenate([_rigid_motion(ri - r0) for ri in r], axis=0)  # (6N, 6), basic axes

    # -- participation and rigid mass about the root, basic axes, model units ----------------
    wt = float(modes.wtmass)
    gpwg = None
    if modes.gpwg_mass is not None:
        ref = modes.gpwg_reference or 0
        if ref == 0:
            r_ref = np.zeros(3)
        elif ref in where:
            r_ref = r[where[ref]]
        else:
            raise NastranError(f"{name}: the GPWG reference grid {ref} is not among the modes' "
                               f"grids")
        T = _rigid_motion(r_ref - r0)  # reference-point motion from the root's
        gpwg = wt * (T.T @ np.asarray(modes.gpwg_mass, dtype=float) @ T)
    generalized = (None if modes.generalized_masses is None
                   else np.asarray(modes.generalized_masses, dtype=float))
    if M_full is not None:
        Phi = phi.reshape(n_all, 6 * n_grids).T
        MPhi = M_full @ Phi
        own = np.einsum("ij,ij->j", Phi, MPhi)
        if generalized is not None and not np.allclose(own, generalized,
                                                       rtol=_GENERALIZED_MASS_RTOL, atol=0):
            k = int(np.argmax(np.abs(own / generalized - 1.0)))
            raise NastranError(
                f"{name}: mass_matrix gives mode {k + 1} the generalized mass {own[k]:.6g}, the "
                f"file {generalized[k]:.6g}: not the solution's mass matrix (WTMASS included), "
                f"or its degrees of freedom in another order than the grids "
                f"{describe(ids.tolist())} x (T1..R3)")
        G = (MPhi.T @ D) / np.sqrt(own)[:, None]
        rigid = D.T @ (M_full @ D)
        if gpwg is not None:
            _compare_rigid(rigid, gpwg, name, "the grid point weight generator's (GPWG)")
    else:
        if gpwg is None and modes.rigid_body_mass is None:
            raise NastranError(f"{name}: no rigid mass: request the grid point weight generator "
                               f"(PARAM,GRDPNT) or give mass_matrix=")
        if gpwg is None:
            ref_T = _rigid_motion(-r0)  # RBMASS about the basic origin (GRDPNT 0) assumed
            gpwg = ref_T.T @ np.asarray(modes.rigid_body_mass, dtype=float) @ ref_T
        rigid = gpwg
        if modes.participation_factors is not None:
            if generalized is None:
                raise NastranError(f"{name}: MEFFMASS participation factors without the "
                                   f"eigenvalue table's generalized masses (LAMA)")
            if wt != 1.0:
                raise NastranError(f"{name}: PARAM,WTMASS = {wt:g}: MEFFMASS output with "
                                   f"WTMASS is not supported; give mass_matrix=")
            ref = modes.gpwg_reference or 0
            r_ref = np.zeros(3) if ref == 0 else r[where[ref]]
            T = _rigid_motion(r_ref - r0)
            G = (np.asarray(modes.participation_factors, dtype=float)
                 * np.sqrt(generalized)[:, None]) @ T
        elif modes.spc_forces is not None and int(root) in set(modes.spc_node_ids.tolist()):
            if generalized is None:
                raise NastranError(f"{name}: SPC forces without the eigenvalue table's "
                                   f"generalized masses (LAMA) cannot be normalised")
            k = int(np.flatnonzero(np.asarray(modes.spc_node_ids) == int(root))[0])
            reaction = np.asarray(modes.spc_forces, dtype=float)[:, k, :]
            G = -reaction / (w**2 * np.sqrt(generalized))[:, None]
        else:
            raise NastranError(
                f"{name}: no participation factors: give mass_matrix= (the solution's mass "
                f"matrix), or write MEFFMASS(PLOT) or SPCFORCES(PLOT) in the case control")

    # -- appendage axes, tip, length, SI -------------------------------------------------------
    Bd = np.kron(np.eye(2), A)  # appendage-axes motion -> basic motion
    G = G @ Bd
    rigid = Bd.T @ rigid @ Bd
    tip_motion = None
    if tip is not None:
        if isinstance(tip, bool) or not isinstance(tip, (int, np.integer)) or int(tip) not in where:
            raise NastranError(f"{name}: tip must be a grid id of the modes; got {describe(tip)}")
        norm = (np.sqrt(own) if M_full is not None else
                np.sqrt(generalized) if generalized is not None else None)
        if norm is None:
            raise NastranError(f"{name}: tip motion needs the modes' generalized masses")
        t = phi[:, where[int(tip)], :] / norm[:, None]
        local = np.concatenate([t[:, :3] @ A, t[:, 3:] @ A], axis=1)
        tip_motion = local[:, [1, 2, 3]]
    if length is None:
        along = (r - r0) @ A[:, 0]
        if M_full is not None:
            diag = np.asarray(M_full.diagonal()).reshape(n_grids, 6)
            along = along[np.any(diag > 0.0, axis=1)]
        length = float(np.max(along)) if along.size and np.max(along) > 0.0 else None
    w_si, G_si, rigid_si, tip_si, length_si = modal_data_to_si(
        w[:keep], G[:keep], rigid, None if tip_motion is None else tip_motion[:keep], length,
        length_unit=length_unit, mass_unit=mass_unit)
    try:
        return ModalAppendage(w_si, G_si, rigid_si, damping=damping, length=length_si,
                              tip_motion=tip_si)
    except ValueError as exc:
        raise NastranError(f"{name}: {exc}") from None


def _check_mass_matrix(mass_matrix, size: int, name: str):
    if hasattr(mass_matrix, "tocsr"):
        M = mass_matrix.tocsr().astype(float)
        finite = np.all(np.isfinite(M.data))
    else:
        M = np.asarray(mass_matrix, dtype=float)
        finite = np.all(np.isfinite(M))
    if M.shape != (size, size):
        raise ValueError(f"mass_matrix must be {size} x {size} (six components per grid of the "
                         f"modes) [model mass units]; got shape {M.shape}")
    if not finite:
        raise ValueError("mass_matrix must be finite [model mass units]")
    asym = abs(M - M.T)
    biggest = float(asym.max()) if size else 0.0
    if biggest > 1e-9 * float(abs(M).max()):
        raise ValueError("mass_matrix must be symmetric [model mass units]")
    diag = np.asarray(M.diagonal())
    if np.any(diag < 0.0):
        raise ValueError(f"mass_matrix must have a non-negative diagonal (masses and inertias) "
                         f"[model mass units]; got {diag.min()!r}")
    return M


def _compare_rigid(rigid: np.ndarray, reference: np.ndarray, name: str, what: str) -> None:
    d = np.sqrt(np.abs(np.diag(reference)))
    scale = np.outer(d, d)
    scale = np.where(scale > 0.0, scale, 1.0)
    worst = np.max(np.abs(rigid - reference) / scale)
    if not math.isfinite(worst) or worst > _RIGID_MASS_RTOL:
        raise NastranError(
            f"{name}: mass_matrix gives a rigid mass about the root that differs from {what} "
            f"by {worst:.2g} (relative): not the solution's mass matrix, or the grids' order")


def read_nastran(path, *, root: int, units, subcase=None, **options) -> ModalAppendage:
    """Read a :class:`~appendages.ModalAppendage` from a NASTRAN normal-modes solution.

    Parameters
    ----------
    path : str or os.PathLike
        An OP2 file (read with pyNastran, :func:`read_op2`) or a ``.npz`` file saved by
        :meth:`NastranModes.save`.
    root, units
        As :func:`modal_appendage`.
    subcase : int, optional
        Which subcase's modes (OP2 files with several).
    **options
        ``axes``, ``mass_matrix``, ``damping``, ``length``, ``tip``, ``n_modes``
        (:func:`modal_appendage`).

    Raises
    ------
    NastranError
        See the module docstring.
    ImportError
        An OP2 file and no working pyNastran.
    """
    name = os.fspath(path)
    if name.lower().endswith(".npz"):
        modes = NastranModes.load(name)
    else:
        modes = read_op2(name, subcase=subcase)
    return modal_appendage(modes, root=root, units=units, **options)
