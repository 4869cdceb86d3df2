r"""Non-uniform beams: uniform segments end to end from the root, and tapered beams.

A solar-array wing is a yoke and panels of other sections; a boom may be thicker at its root. A
:class:`SteppedBeam` is such an appendage as uniform :class:`~appendages.beam.Beam` segments joined
end to end from the attachment end, optionally with a :class:`~appendages.tip.TipBody` at the free
end. Its W(s) and W6(s) are exact: the segments' exact member dynamic stiffness matrices are
assembled at the joints and condensed to the root (:mod:`appendages.assembly`), so nothing
overflows or cancels at any |s| and no transfer matrix is multiplied along the beam; its natural
frequencies come from a Wittrick-Williams count, its truncations from the exact modes
(:class:`~appendages.modal.ModalBeam`), its damping is the modal damping of its cantilever modes.

A tapered beam (:meth:`SteppedBeam.tapered`) is approximated by n uniform segments whose section
dimensions are those at each segment's middle: the midpoint rule of a smooth variation, whose
frequencies converge like n**-2 (measured in the tests and benchmarks/results/tip_stepped.md).

References
----------
.. [1] W. H. Wittrick, F. W. Williams, "A general algorithm for computing natural frequencies of
   elastic structures", Q. J. Mech. Appl. Math. 24(3), 1971.
.. [2] J. R. Banerjee, F. W. Williams, "Exact Bernoulli-Euler dynamic stiffness matrix for a
   range of tapered beams", Int. J. Numer. Meth. Eng. 21, 1985 (stepped approximations of
   tapered members and their convergence).
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np

from . import limits
from .assembly import Segment
from .beam import Beam
from .checks import check_range
from .errors import describe
from .modal import ModalBeam
from .segmented import SegmentedBeam
from .tip import TipBody, check_tip

__all__ = ["SteppedBeam", "SECTIONS"]

#: The section constructors a tapered beam interpolates, and their dimensions [m].
SECTIONS = {"circular_rod": ("diameter",), "tube": ("outer_diameter", "wall_thickness"),
            "rectangular": ("width", "thickness")}

_OPTIONAL = ("torsional_inertia", "torsional_stiffness", "axial_stiffness")


def _check_segments(segments) -> tuple:
    """The segments as a tuple of bare Beams, checked (module docstring of SteppedBeam)."""
    if isinstance(segments, (str, bytes, Beam)) or not isinstance(segments, Sequence):
        raise TypeError(f"segments must be a sequence of Beam (uniform segments from the root); "
                        f"got {type(segments).__name__} {describe(segments)}")
    segments = tuple(segments)
    if not segments:
        raise ValueError("segments must hold at least one Beam; got an empty sequence")
    limits.check("len(segments)", len(segments), "segments", "segments of a stepped beam")
    for k, segment in enumerate(segments):
        if not isinstance(segment, Beam):
            raise TypeError(f"segments[{k}] must be a Beam (a uniform segment); got "
                            f"{type(segment).__name__} {describe(segment)}")
        if segment.tip is not None and not segment.tip.is_null:
            raise ValueError(f"segments[{k}].tip: a segment carries no tip body; give the body "
                             f"to SteppedBeam(segments, tip=...); got {segment.tip!r}")
        if segment.damping_ratio != segments[0].damping_ratio:
            raise ValueError(
                f"segments[{k}].damping_ratio must equal segments[0].damping_ratio (one modal "
                f"damping ratio for the cantilever modes of the whole beam) [-]; got "
                f"{segment.damping_ratio!r} and {segments[0].damping_ratio!r}")
    for name in _OPTIONAL:
        given = [getattr(segment, name) is not None for segment in segments]
        if any(given) and not all(given):
            k = given.index(not given[0])
            raise ValueError(
                f"segments[{k}].{name} is {'None' if given[0] else 'given'} while "
                f"segments[0].{name} is {'given' if given[0] else 'None'}: the three-axis "
                "properties must be given for every segment or for none (a segment without "
                "torsional or axial stiffness is rigid in that motion, a whole beam or none)")
    return segments


class SteppedBeam(SegmentedBeam):
    """Uniform :class:`~appendages.beam.Beam` segments end to end from the root (module
    docstring).

    Parameters
    ----------
    segments : sequence of Beam
        From the attachment end outward, each with its own length, stiffnesses and density.
        Segments carry no tip body, share one ``damping_ratio`` (the modal damping ratio of
        every cantilever mode of the stepped beam), and have the three-axis properties
        (``torsional_inertia``, ``torsional_stiffness``, ``axial_stiffness``) all or none.
    tip : TipBody, optional
        A rigid body at the free end.

    Raises
    ------
    TypeError
        segments not a sequence of Beam, tip not a TipBody.
    ValueError
        No segment, a segment with a tip body, damping ratios that differ, three-axis
        properties given for some segments only (the message names the segment and the
        property), more segments than the ``segments`` limit of :mod:`appendages.limits`.

    Attributes
    ----------
    segments : tuple of Beam
    tip : TipBody or None
    damping_ratio : float
    """

    def __init__(self, segments: Sequence[Beam], *, tip: TipBody | None = None):
        segments = _check_segments(segments)
        tip = check_tip(tip)
        self.segments = segments
        properties = [Segment(b.length, b.bending_stiffness, b.linear_density,
                              b.bending_stiffness_y if b.three_axis else None,
                              b.torsional_stiffness, b.torsional_inertia, b.axial_stiffness)
                      for b in segments]
        super().__init__(properties, None if tip is None or tip.is_null else tip,
                         segments[0].damping_ratio)
        self.tip = tip

    def __repr__(self) -> str:
        tip = "" if self.tip is None else f", tip={self.tip!r}"
        return (f"SteppedBeam({len(self.segments)} segments, length={self.length:.6g} m, "
                f"mass={self.mass:.6g} kg{tip})")

    def undamped(self) -> "SteppedBeam":
        """The same beam without damping (itself when undamped)."""
        if self.damping_ratio == 0.0:
            return self
        cached = self._cache.get("undamped")
        if cached is None:
            cached = self._cache["undamped"] = SteppedBeam(
                [segment.undamped() for segment in self.segments], tip=self.tip)
        return cached

    def planar_view(self, plane: str = "xy") -> "SteppedBeam":
        """The planar stepped beam of one bending plane (:meth:`Beam.planar_view`)."""
        if plane not in ("xy", "xz"):
            raise ValueError(f"plane must be 'xy' or 'xz'; got {describe(plane)}")
        tip = None
        if self.tip is not None:
            t = self.tip
            tip = (TipBody(t.mass, t.planar_inertia, t.offset[:2]) if plane == "xy" else
                   TipBody(t.mass, float(t.inertia_tensor[1, 1]), t.offset[[0, 2]]))
        return SteppedBeam([segment.planar_view(plane) for segment in self.segments], tip=tip)

    def truncated(self, n_modes: int, *, method: str = "craig-bampton"):
        """A finite modal model with ``n_modes`` modes (:class:`~appendages.modal.ModalBeam`):
        ``"craig-bampton"`` (default: root motion and the first cantilever modes),
        ``"residual"`` or ``"free-free"``, all built from the exact modes."""
        return ModalBeam(self, n_modes, method=method)

    @classmethod
    def tapered(cls, length: float, n_segments: int, *, section: str, root_dimensions: dict,
                tip_dimensions: dict, density: float, youngs_modulus: float,
                poisson_ratio: float = 0.3, damping_ratio: float = 0.0,
                tip: TipBody | None = None) -> "SteppedBeam":
        """A beam whose section dimensions vary linearly from the root to the free end,
        as n uniform segments (module docstring).

        Segment k (from ``k L/n`` to ``(k + 1) L/n``) has the dimensions at its middle,
        ``d = d_root + (d_tip - d_root) (k + 1/2)/n``, and the section constructor's
        properties (:meth:`Beam.circular_rod`, :meth:`Beam.tube`, :meth:`Beam.rectangular`).

        Parameters
        ----------
        length : float, m
        n_segments : int
            At least 1; the frequencies converge like n_segments**-2.
        section : {"circular_rod", "tube", "rectangular"}
        root_dimensions, tip_dimensions : dict of float, m
            The section's dimensions (:data:`SECTIONS`) at the root and at the free end, e.g.
            ``{"outer_diameter": 0.1, "wall_thickness": 0.002}`` for a tube.
        density : float, kg/m**3
        youngs_modulus : float, Pa
        poisson_ratio : float, optional
        damping_ratio : float, optional
            Modal damping ratio of the cantilever modes.
        tip : TipBody, optional
        """
        length = check_range("length", length, "length")
        if isinstance(n_segments, (bool, np.bool_)) or not isinstance(n_segments,
                                                                      (int, np.integer)):
            raise TypeError(f"n_segments must be an integer; got {type(n_segments).__name__} "
                            f"{describe(n_segments)}")
        if n_segments < 1:
            raise ValueError(f"n_segments must be at least 1; got {describe(n_segments)}")
        limits.check("n_segments", int(n_segments), "segments", "segments of a stepped beam")
        if not isinstance(section, str) or section not in SECTIONS:
            raise ValueError(f"section must be one of {tuple(SECTIONS)}; got {describe(section)}")
        names = SECTIONS[section]
        ends = []
        for label, dimensions in (("root_dimensions", root_dimensions),
                                  ("tip_dimensions", tip_dimensions)):
            if not isinstance(dimensions, dict) or set(dimensions) != set(names):
                raise ValueError(f"{label} must be a dict with exactly the keys {names} of a "
                                 f"{section} [m]; got {describe(dimensions)}")
            values = {}
            for name in names:
                value = dimensions[name]
                if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
                    raise TypeError(f"{label}['{name}'] must be a real number [m]; got "
                                    f"{type(value).__name__} {describe(value)}")
                values[name] = check_range(f"{label}['{name}']", value, "length")
            ends.append(values)
        constructor = getattr(Beam, section)
        n = int(n_segments)
        segments = []
        for k in range(n):
            xi = (k + 0.5) / n
            dims = {name: ends[0][name] + (ends[1][name] - ends[0][name]) * xi for name in names}
            segments.append(constructor(length / n, *dims.values(), density, youngs_modulus,
                                        poisson_ratio=poisson_ratio,
                                        damping_ratio=damping_ratio))
        return cls(segments, tip=tip)
