"""What the report says about an appendage's structure: a beam, a stepped or tapered beam, a
tip body, modal data, one line each, read from the resolved scene (``scene_dict``).

:func:`structure_text` is the parenthesis after an appendage's name in the report's section
"The question"; :func:`truth_text` names its truth model. Numbers are SI (the resolved scene's),
to 5 significant digits.
"""

from __future__ import annotations

__all__ = ["structure_text", "truth_text"]


def _n(value, digits: int = 5) -> str:
    return f"{float(value):.{digits}g}"


def _dimensions(dims: dict) -> str:
    return ", ".join(f"{k} {_n(v)}" for k, v in dims.items())


def _material(spec: dict) -> str:
    if not spec.get("density"):
        return ""
    return f", density {_n(spec['density'])} kg/m^3, E {_n(spec['youngs_modulus'])} Pa"


def _tip(tip: dict | None) -> str:
    if not tip:
        return ""
    inertia = tip["inertia"]
    inertia = (f"{_n(inertia)} kg m^2" if not isinstance(inertia, list)
               else "inertia tensor [" + "; ".join(", ".join(_n(v, 4) for v in row)
                                                  for row in inertia) + "] kg m^2")
    offset = tip["offset"]
    offset = (f"{_n(offset)} m" if not isinstance(offset, list)
              else "(" + ", ".join(_n(v, 4) for v in offset) + ") m")
    return f"; tip body {_n(tip['mass'])} kg, {inertia}, centre {offset} beyond the free end"


def structure_text(appendage: dict) -> str:
    """`` (rod, length 10 m, ...; tip body 5 kg, ...)`` for one appendage of the resolved
    scene, or ``""`` for a chain alone."""
    spec = appendage.get("beam")
    if spec:
        kind = spec.get("kind", "beam")
        if kind == "stepped_beam":
            parts = [f"{s['section']} {_n(s['length'])} m ({_dimensions(s['dimensions'])})"
                     for s in spec["segments"]]
            body = (f"stepped beam of {len(parts)} segments from the root: " + "; ".join(parts)
                    + f", damping ratio {_n(spec['damping_ratio'])}")
        elif kind == "tapered_beam":
            ends = ", ".join(f"{k} {_n(v)} to {_n(spec['tip_dimensions'][k])}"
                             for k, v in spec["root_dimensions"].items())
            body = (f"tapered {spec['section']}, length {_n(spec['length'])} m, {ends} m as "
                    f"{spec['n_segments']} uniform segments{_material(spec)}, damping ratio "
                    f"{_n(spec['damping_ratio'])}")
        else:
            body = (f"{spec['section']}, length {_n(spec['length'])} m, "
                    f"{_dimensions(spec['dimensions'])}{_material(spec)}, damping ratio "
                    f"{_n(spec['damping_ratio'])}")
        return f" ({body}{_tip(spec.get('tip'))})"
    modal = appendage.get("modal")
    if modal:
        where = {"file": f"modal data file {modal.get('path')}",
                 "nastran": f"NASTRAN solution {modal.get('path')}",
                 "inline": "modal data given in the scene"}[modal["source"]]
        low, high = modal["damping_range"]
        damping = (f", damping ratio {_n(low)}" if low == high else
                   f", damping ratios {_n(low)} to {_n(high)}")
        return (f" ({where}: {modal['n_modes']} cantilever modes, "
                f"{_n(modal['first_frequency'])} to {_n(modal['last_frequency'])} rad/s, "
                f"mass {_n(modal['mass'])} kg{damping})")
    return ""


def truth_text(appendage: dict) -> str:
    """The truth model's kind: a distributed beam, modal data (FE-exact) or a chain."""
    return {"beam": "distributed beam", "modal": "its modal data (FE-exact: all its modes)",
            "chain": "chain"}[appendage["truth"]]
