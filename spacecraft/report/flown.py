"""The report's sections on the manoeuvre as flown (:mod:`spacecraft.design.manoeuvre`).

After the closed loops, in the order a review asks:

- the reference profile per design model: its kind, peaks, limits and the shortest time they
  allow, the shaper (impulses, the modes it cancels, its robustness band, what it leaves on the
  truth model's modes), how exactly the loop reads it;
- the delay margins of every loop on the design model, the truth model and the exact beam
  (the extra delay each tolerates, with its delay; red where the delay destabilised it);
- the metrics measured against the end of the profile (during: peak attitude error and
  torque; after: residual vibration and settling), beside the table from t = 0;
- the reaction wheels: torque and momentum against their limits, the time saturated, the
  momentum margin, the run in words (orange when a wheel saturated); Basilisk's wheel in the
  same words when the scene runs it;
- the pointing figures under the sensors' noise (APE, MPE, RPE per axis and the tip jitter,
  1 sigma and at the scene's probability), with the ECSS definitions they follow.

:func:`flown_summary_lines` adds the delay margins, the wheels and the pointing to the
summary.
"""

from __future__ import annotations

import math

from ..design.manoeuvre import MANOEUVRE_METRIC_LABELS
from ..design.naming import controller_label, design_label
from .pages import bad, number, warn

__all__ = ["flown_blocks", "flown_summary_lines", "basilisk_wheel_blocks", "ARCSEC"]

#: Radians per arcsecond (the pointing figures are also shown in arcsec).
ARCSEC = math.pi / (180.0 * 3600.0)


def _who(row: dict) -> str:
    return f"{controller_label(row['controller'])} tuned on {design_label(row['design'])}"


def _deg(value, digits: int = 4) -> str:
    return "n/a" if value is None else number(math.degrees(value), digits)


def _about(facts: dict) -> str:
    """Three axes: the eigen-axis the profile turns about."""
    axis = facts.get("axis")
    if axis is None:
        return ""
    return (" about the eigen-axis (" + ", ".join(number(e, 4) for e in axis)
            + ") in hub axes")


def _feedforward_words(inertia) -> str:
    """The feedforward torque in words: J alpha_ref (planar), J alpha_ref + omega_ref x J
    omega_ref (three axes, J the tensor in hub axes)."""
    if isinstance(inertia, (list, tuple)):
        J = "[" + "; ".join(", ".join(number(v, 4) for v in row) for row in inertia) + "]"
        return ("J alpha_ref + omega_ref x J omega_ref with J = " + J + " kg m^2 (the design "
                "model's rigid-body inertia tensor, hub axes) and the rate reference")
    return ("J alpha_ref with J = " + number(inertia) + " kg m^2 (the design model's "
            "rigid-body inertia) and the rate reference")


def _profile_items(facts: dict, scene: dict) -> list:
    m = scene.get("manoeuvre") or {}
    kind = facts["kind"]
    items = []
    if kind == "step":
        items.append(f"step reference: the cycloid of theta_ref from 0 to "
                     f"{_deg(m.get('slew_angle'))} deg in {number(facts['end_time'])} s, no rate "
                     "reference, no feedforward")
    else:
        shaper = facts.get("shaper")
        base = shaper["base"] if shaper else kind
        items.append(f"{kind}" + (f" ({shaper['kind'].upper()} shaper convolved with a {base} "
                                  "profile)" if shaper else "")
                     + _about(facts)
                     + f", ending at t = {number(facts['end_time'])} s; feedforward "
                     + (_feedforward_words(facts["inertia"]) if facts["feedforward"]
                        else "off: the controller reads theta_ref"))
        limits = [f"{label} {value}" for label, value in (
            ("torque", None if m.get("torque_limit") is None
             else number(m["torque_limit"], 4) + " N m"),
            ("rate", None if m.get("rate_limit") is None
             else _deg(m["rate_limit"]) + " deg/s"),
            ("jerk", None if m.get("jerk_limit") is None
             else _deg(m["jerk_limit"]) + " deg/s^3")) if value is not None]
        items.append(f"peaks: rate {_deg(facts['peak_rate'])} deg/s, acceleration "
                     f"{_deg(facts['peak_acceleration'])} deg/s^2, feedforward torque "
                     f"{number(facts['peak_torque'], 4)} N m; limits: "
                     + (", ".join(limits) if limits else "none")
                     + (f"; the shortest slew they allow: "
                        f"{number(facts.get('profile_shortest_time'), 4)} s"
                        if facts.get("profile_shortest_time") is not None else ""))
        if shaper:
            modes = "; ".join(
                f"{number(mode['frequency'], 4)} rad/s (damping {number(mode['damping_ratio'], 3)}"
                f"), residual vibration below {100 * shaper['tolerance']:.3g} % for "
                f"{100 * (mode['band'][0] - 1):+.3g} % to {100 * (mode['band'][1] - 1):+.3g} % "
                "frequency error" for mode in shaper["modes"])
            items.append(f"shaper: {len(shaper['times'])} impulses over "
                         f"{number(shaper['duration'], 4)} s (times "
                         + ", ".join(number(t, 4) for t in shaper["times"]) + " s, amplitudes "
                         + ", ".join(number(a, 4) for a in shaper["amplitudes"])
                         + f"), on the design model's modes: {modes}")
            for r in facts.get("truth_residual", []):
                text = (f"on the truth model the mode lies at {number(r['truth_frequency'], 4)} "
                        f"rad/s ({100 * r['frequency_error']:+.3g} %): the shaper leaves "
                        f"{100 * r['residual_vibration']:.3g} % of the unshaped vibration")
                items.append(warn(text) if r["residual_vibration"] > shaper["tolerance"]
                             else text)
    if facts.get("wheels_shortest_time") is not None:
        items.append(f"the wheels' torque and momentum limits allow the slew in no less than "
                     f"{number(facts['wheels_shortest_time'], 4)} s")
    hold = facts.get("hold_error")
    reading = facts.get("reading")
    if kind != "step" and reading == "samples":
        items.append("the digital controller reads the references at its samples (exact)")
    elif kind != "step" and reading == "held":
        items.append("the delayed continuous loop holds its command over each step: the "
                     "controller reads the references at the samples (the rate reference and "
                     "the feedforward torque as their means over the step centred there, exact "
                     "impulses across the acceleration's jumps); second order in the step")
    elif hold and kind != "step":
        units = {"theta_ref": "rad", "omega_ref": "rad/s", "torque_ff": "N m"}
        items.append("the loop reads the references at the samples, linearly interpolated "
                     "between them: they differ from the exact profile by at most "
                     + ", ".join(f"{number(v, 3)} {units.get(k, '')} ({k})"
                                 for k, v in hold.items())
                     + " (the torque's where the acceleration jumps between two samples, for "
                       "a part of a step)")
    return items


def _delay_rows(rows: list) -> tuple[list, list]:
    exact = any("delay_margin" in (r.get("exact_verdict") or {}) for r in rows)
    header = ["loop", "delay [s]", "delay margin on the design model [s]",
              "on the truth model [s]"] + (["on the exact beam [s]"] if exact else [])
    out = []
    for r in rows:
        cells = [_who(r), number(r["verdict"].get("delay"), 4)]
        for source in (r.get("design_margins") or {}, r["verdict"]) + (
                (r.get("exact_verdict") or {},) if exact else ()):
            value = source.get("delay_margin")
            text = number(value, 4)
            if source.get("stable") is False:
                cells.append(bad(f"{text} (UNSTABLE with its delay)"))
            else:
                cells.append(text)
        out.append(cells)
    return header, out


def _cell(row: dict, which: str, name: str):
    flag = (row.get("manoeuvre_flags") or {}).get(which, {}).get(name)
    if flag == "diverges":
        return bad("diverges")
    if flag is not None:
        return warn(flag)
    return number((row.get("manoeuvre_metrics") or {}).get(which, {}).get(name), 4)


def _metric_blocks(rows: list, end: float | None) -> list:
    mine = [r for r in rows if r.get("manoeuvre_metrics")]
    if not mine:
        return []
    b: list = [("h3", "Measured against the end of the profile"),
               ("p", f"From the end of the profile at t = {number(end)} s: during it (t up to "
                     "its end) the peak attitude error |theta - theta_ref| and the peak torque; "
                     "after it the residual vibration (the largest attitude error and tip "
                     "deflection left) and the settling time (2 % band) counted from its end. "
                     "The slew tables above count from t = 0 (their settling time includes "
                     "the profile).")]
    for kind in dict.fromkeys(r["controller"] for r in mine):
        loops = [r for r in mine if r["controller"] == kind]
        header = ["metric"] + [f"{design_label(r['design'])}: on {which} model"
                               for r in loops for which in ("design", "truth")]
        table = []
        for name, label in MANOEUVRE_METRIC_LABELS.items():
            if not any(name in r["manoeuvre_metrics"].get("truth", {}) for r in loops):
                continue
            table.append([label] + [_cell(r, which, name) for r in loops
                                    for which in ("design", "truth")])
        b.append(("h3", f"{controller_label(kind)}: during and after the profile"))
        b.append(("table", header, table))
    return b


def _limit(values, names, wheel) -> float | None:
    if values is None:
        return None
    return values[names.index(wheel)] if wheel in names else None


def _wheel_blocks(data: dict) -> list:
    rows = [r for r in data.get("closed_loops", []) if r.get("wheels")]
    spec = (data.get("manoeuvre") or {}).get("wheels")
    if not rows or spec is None:
        return []
    names = spec["names"]
    b: list = [("h3", "Reaction wheels"),
               ("p", f"{len(names)} wheel{'s' * (len(names) != 1)}: torque limit "
                     + ", ".join(number(v, 4) for v in spec["torque_limits"]) + " N m, momentum "
                     "limit " + ", ".join(number(v, 4) for v in spec["momentum_limits"])
                     + f" N m s; a command beyond the torque limit is reduced by "
                       f"'{spec['saturation']}'; a wheel at its momentum limit stops taking "
                       f"momentum. Simulated {spec['method']}. The slew and the disturbance "
                       "together (the wheels are nonlinear).")]
    header = ["loop", "model", "wheel", "peak torque [N m] (limit)",
              "peak momentum [N m s] (limit)", "time at the torque limit [s]",
              "time at the momentum limit [s]", "momentum margin [N m s]", "in words"]
    table = []
    for r in rows:
        for which, s in r["wheels"].items():
            for k, wheel in enumerate(s["peak_torque"]):
                margin = s["momentum_margin"][wheel]
                fraction = s["momentum_margin_fraction"][wheel]
                words = s["words"]
                table.append([
                    _who(r), which, wheel,
                    f"{number(s['peak_torque'][wheel], 4)} "
                    f"({number(_limit(spec['torque_limits'], names, wheel), 4)})",
                    f"{number(s['peak_momentum'][wheel], 4)} "
                    f"({number(_limit(spec['momentum_limits'], names, wheel), 4)})",
                    number(s["time_torque_saturated"][wheel], 4),
                    number(s["time_momentum_saturated"][wheel], 4),
                    f"{number(margin, 4)}" + ("" if fraction is None else
                                              f" ({100 * fraction:.3g} %)"),
                    "" if k else warn(words) if s["saturated"] else words])
    b.append(("table", header, table))
    return b


def _pointing_blocks(data: dict) -> list:
    rows = [r for r in data.get("closed_loops", []) if r.get("pointing")]
    if not rows:
        return []
    first = next(iter(rows[0]["pointing"].values()))
    sensors = (data.get("scene_resolved") or {}).get("sensors") or {}
    levels = ", ".join(f"{label} {number(sensors.get(key), 3)} {unit}" for key, label, unit in (
        ("attitude_density", "attitude sensor", "rad/sqrt(Hz)"),
        ("angle_random_walk", "gyro angle random walk", "rad/sqrt(s)"),
        ("bias_instability", "bias instability", "rad/s")) if sensors.get(key))
    if sensors.get("bias_correlation_time"):
        levels += f" (correlation time {number(sensors['bias_correlation_time'], 4)} s)"
    probability = sensors.get("probability", 0.9973)
    b: list = [("h3", "Pointing under the sensors' noise"),
               ("p", f"Noise: {levels}. Window {number(first.get('window'))} s. Definitions: "
                     + (first.get("definitions") or "ECSS-E-ST-60-10C") + ". 1 sigma, and at "
                     f"{100 * probability:.4g} % (two-sided Gaussian); attitude in rad "
                     "(arcsec in brackets), tip jitter in m.")]
    header = ["loop", "model", "output", "APE (1 sigma)", "MPE (1 sigma)", "RPE (1 sigma)",
              f"APE ({100 * probability:.4g} %)", f"RPE ({100 * probability:.4g} %)"]
    table = []
    for r in rows:
        for which, p in r["pointing"].items():
            if "error" in p:
                said = (warn(f"not computed: {p['error']}") if p.get("not_computed")
                        else bad(p["error"]))
                table.append([_who(r), which, "-", said, "", "", "", ""])
                continue
            for kind, mean, rel in (("ape", "mpe", "rpe"), ("jitter", "jitter_mpe",
                                                             "jitter_rpe")):
                for name, value in p[kind].items():
                    angle = kind == "ape"

                    def show(v, angle=angle):
                        return (f"{number(v, 3)} ({number(v / ARCSEC, 3)}\")" if angle
                                else number(v, 3))
                    table.append([_who(r), which, name, show(value), show(p[mean][name]),
                                  show(p[rel][name]), show(p["at"][kind][name]),
                                  show(p["at"][rel][name])])
    b.append(("table", header, table))
    return b


def flown_blocks(data: dict) -> list:
    """The report's blocks on the manoeuvre as flown (module docstring); empty without a
    manoeuvre."""
    facts = data.get("manoeuvre")
    rows = data.get("closed_loops", [])
    if not facts or not rows:
        return []
    scene = data.get("scene_resolved") or {}
    delay = facts.get("delay") or {}
    b: list = [("h2", "The manoeuvre as flown" if facts.get("flown") else
                "The manoeuvre: its profile, the delay margins, the slew from its end")]
    parts = []
    profiles = facts.get("profiles") or {}
    kinds = {f["kind"] for f in profiles.values()}
    m = scene.get("manoeuvre") or {}
    if kinds:
        parts.append("the reference: " + ", ".join(sorted(kinds)) + " profile"
                     + (", fed forward (rate reference and torque)" if m.get("feedforward")
                        else ""))
    else:   # not flown: the cycloidal slew of slew_time, no feedforward
        parts.append("the reference: the cycloidal slew of "
                     f"{number(m.get('slew_time'), 4)} s, not fed forward")
    if delay.get("total"):
        parts.append(f"a loop delay of {number(delay['total'], 4)} s"
                     + (" (one sample of computation included)"
                        if delay.get("computation_delay") else ""))
    if facts.get("wheels"):
        parts.append("reaction wheels")
    if any(r.get("pointing") for r in rows):
        parts.append("sensor noise")
    b.append(("p", "; ".join(parts) + "."))
    for variant, f in profiles.items():
        b.append(("h3", f"Reference profile for the controllers tuned on {design_label(variant)}"))
        b.append(("ul", _profile_items(f, scene)))
    b.append(("h3", "Delay margins"))
    b.append(("p", "The delay margin is the extra loop delay a loop tolerates before it "
                   "goes unstable: the smallest phase margin over frequency, PM / omega_c, "
                   "over every gain crossover, with the loop's own delay included (exactly: "
                   "e^(-j omega tau) on L). A delay at or beyond it is no error but a result: "
                   "the loop is unstable, in red."))
    header, table = _delay_rows(rows)
    b.append(("table", header, table))
    end = next(iter(profiles.values()))["end_time"] if profiles else m.get("slew_time")
    b += _metric_blocks(rows, end)
    b += _wheel_blocks(data)
    b += _pointing_blocks(data)
    return b


def flown_summary_lines(data: dict) -> list:
    """Summary lines: per loop its delay margin on the truth model (when the loop has a
    delay), a wheel that saturated, and the pointing on the truth model."""
    lines = []
    delay = ((data.get("manoeuvre") or {}).get("delay") or {}).get("total")
    for r in data.get("closed_loops", []):
        parts = []
        v = r["verdict"]
        if delay and v.get("delay_margin") is not None and v.get("stable"):
            parts.append(f"delay margin {number(v['delay_margin'], 3)} s beyond its "
                         f"{number(delay, 3)} s delay")
        p = (r.get("pointing") or {}).get("truth")
        if p and "error" not in p:
            ape = max(p["ape"].values())
            rpe = max(p["rpe"].values())
            parts.append(f"pointing APE {number(ape / ARCSEC, 3)}\", RPE "
                         f"{number(rpe / ARCSEC, 3)}\" (1 sigma, truth model)")
        w = (r.get("wheels") or {}).get("truth")
        if w is not None:
            parts.append(warn(w["words"]) if w["saturated"] else "wheels within their limits")
        if parts:
            text = f"{_who(r)}: " + "; ".join(str(p) for p in parts)
            lines.append(warn(text) if w is not None and w["saturated"] else text)
    return lines


def basilisk_wheel_blocks(kind: str, entry: dict) -> list:
    """Basilisk's reaction wheel in one controller's Basilisk run, in the words of flexsat's
    wheels (:func:`spacecraft.design.simulators.basilisk_wheel_summary`): orange when it
    saturated, with the time saturated and the momentum margin."""
    w = entry.get("wheel")
    if not w:
        return []
    text = (f"{controller_label(kind)}, Basilisk's reaction wheel: {w['words']}; peak torque "
            f"applied {number(w['peak_torque']['wheel'], 4)} N m, peak momentum "
            f"{number(w['peak_momentum']['wheel'], 4)} N m s")
    return [("p", warn(text) if w["saturated"] else text)]
