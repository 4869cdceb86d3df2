"""The report's modal table of the open-loop coupled spacecraft (its truth model).

One row per coupled elastic mode (:func:`spacecraft.dynamics.survey.modal_survey`, in
``results.json`` under ``truth.modes``): frequency [rad/s] and [Hz], damping ratio, torque
participation, and each appendage's share of the mode's strain energy; beside it, the damping
ratios the scene entered, so that what was entered and what results can be compared at a
glance.
"""

from __future__ import annotations

__all__ = ["modal_table_blocks", "entered_damping"]


def _n(value, digits: int = 4) -> str:
    return f"{float(value):.{digits}g}"


def entered_damping(scene: dict) -> list[str]:
    """``"wing: 0.005 (its cantilever modes)"`` per appendage of the resolved scene that has a
    damping ratio (a beam's, modal data's), in scene order."""
    out = []
    for a in scene.get("appendages", []):
        if a.get("beam"):
            text = _n(a["beam"]["damping_ratio"])
        elif a.get("modal"):
            low, high = a["modal"]["damping_range"]
            text = _n(low) if low == high else f"{_n(low)} to {_n(high)}"
        else:
            continue
        out.append(f"{a['name']}: {text} (its cantilever modes)")
    return out


def modal_table_blocks(data: dict) -> list:
    """The report's blocks: a heading, what the columns are, the entered damping ratios and
    the table; nothing when the run has no modal survey."""
    modes = data.get("truth", {}).get("modes")
    if not modes:
        return []
    three_axis = len(modes[0]["torque_participation"]) == 3
    names = list(modes[0]["strain_energy"])
    header = ["mode", "frequency [rad/s]", "frequency [Hz]", "damping ratio"]
    header += ([f"torque participation {a}" for a in "xyz"] if three_axis
               else ["torque participation"])
    header += [f"{name}: strain energy" for name in names]
    rows = []
    for k, m in enumerate(modes):
        row = [k + 1, _n(m["frequency"], 5), _n(m["frequency_hz"], 5), _n(m["damping_ratio"])]
        # below 1e-12: round-off of a mode that torque cannot reach (mirror-image wings)
        row += [_n(p, 3) if p >= 1e-12 else "0" for p in m["torque_participation"]]
        row += [f"{100.0 * m['strain_energy'][name]:.1f} %" for name in names]
        rows.append(row)
    blocks = [("h3", "Modes of the open-loop spacecraft (truth model)"),
              ("p", "Each coupled elastic mode of the truth model without control: its "
                    "frequency and damping ratio (of its damped pole), its torque "
                    "participation (its residue in theta/torque relative to the rigid body's "
                    "1/J: 0 for a mode a torque cannot excite) and each appendage's share of "
                    "its strain energy (which appendage deforms).")]
    entered = entered_damping(data.get("scene_resolved", {}))
    if entered:
        blocks.append(("p", "Damping ratios entered: " + "; ".join(entered) + "."))
    blocks.append(("table", header, rows))
    return blocks
