"""The FMU's own documentation: ``documentation/index.html``, the icon and the licences.

``documentation/index.html`` (FMI 3.0.2, section 2.5.1.1; FMI 2.0 names its entry point
``documentation/_main.html``, written with the same content) states what the FMU computes:
the equations, every variable with its causality, unit, start value and nominal, the
matrices A, B, C, D (in full up to :data:`MAX_DOCUMENTED_ENTRIES` entries; larger models
point to ``sources/model.c``, which holds them exactly), the poles with their natural
frequencies and damping ratios, the default experiment and the capabilities (sampling,
FMU states, partial derivatives).

The icon (``model.png`` of FMI 2.0, ``documentation/diagram.png`` of FMI 3.0) is a block
with one arrow per input and output and, inside, a smooth response for a continuous-time
model or a staircase for a sampled one; it is drawn here pixel by pixel and written as a
PNG with :mod:`zlib`, so that no plotting library is imported for it.

References
----------
FMI 2.0.1 standard, section 2.3 (FMU distribution: ``model.png``, ``documentation``);
FMI 3.0.2 standard, section 2.5.1 (``documentation/index.html``, ``licenses``);
W3C, "Portable Network Graphics (PNG) Specification (Second Edition)", 2003.
"""

from __future__ import annotations

import html
import math
import struct
import zlib

import numpy as np

from .codegen import c_double
from .description import variable_units
from .system import LinearModel

__all__ = ["MAX_DOCUMENTED_ENTRIES", "documentation_html", "icon_png", "licence_text"]

#: Largest number of matrix entries (all of A, B, C, D) written out in index.html.
MAX_DOCUMENTED_ENTRIES = 4000
#: Largest number of states whose poles are listed (an eigenvalue problem of that order).
_MAX_POLE_STATES = 400

_STYLE = """body{font-family:sans-serif;max-width:60em;margin:2em auto;line-height:1.4}
table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #bbb;padding:2px 6px;
text-align:right;font-family:monospace}th{background:#eee}td.name,th.name{text-align:left}
code{background:#f4f4f4}"""


def _matrix(label: str, matrix: np.ndarray, rows: tuple[str, ...], columns: tuple[str, ...]) -> str:
    if matrix.size == 0:
        return f"<p>{label} is empty ({matrix.shape[0]} &times; {matrix.shape[1]}).</p>\n"
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = "".join(
        f'<tr><th class="name">{html.escape(r)}</th>'
        + "".join(f"<td>{c_double(v)}</td>" for v in row) + "</tr>\n"
        for r, row in zip(rows, matrix.tolist()))
    return (f"<h3>{label} ({matrix.shape[0]} &times; {matrix.shape[1]})</h3>\n"
            f"<table><tr><th></th>{head}</tr>\n{body}</table>\n")


def _poles(model: LinearModel) -> str:
    n = model.n_states
    if n == 0:
        return "<p>No states: a static gain.</p>\n"
    if n > _MAX_POLE_STATES:
        return f"<p>{n} states: the poles are not listed here (more than {_MAX_POLE_STATES}).</p>\n"
    with np.errstate(all="ignore"):
        eigenvalues = np.linalg.eigvals(model.A)
    order = np.argsort(np.abs(eigenvalues), kind="stable")
    rows = []
    for z in eigenvalues[order]:
        if model.discrete:
            # s = log(z) / T: the continuous pole the sampled one corresponds to
            s = complex(np.log(z)) / model.sample_period if z != 0 else complex(-np.inf)
        else:
            s = complex(z)
        frequency = abs(s)
        damping = -s.real / frequency if frequency > 0 and np.isfinite(frequency) else float("nan")
        shown = f"{z.real:.6g} {'+' if z.imag >= 0 else '-'} {abs(z.imag):.6g}j"
        rows.append(f"<tr><td>{shown}</td><td>{frequency:.6g}</td><td>{damping:.4g}</td></tr>")
    what = ("z (eigenvalue of A)" if model.discrete else "s (eigenvalue of A) [1/s]")
    note = ("<p>For the sampled model, &omega;<sub>n</sub> and &zeta; are those of "
            "s = ln(z)/T.</p>\n" if model.discrete else "")
    return (f"{note}<table><tr><th>{what}</th><th>&omega;<sub>n</sub> [rad/s]</th>"
            f"<th>&zeta;</th></tr>\n" + "\n".join(rows) + "</table>\n")


def documentation_html(model: LinearModel, *, model_identifier: str, fmi_version: str,
                       interfaces: tuple[str, ...], step: float, stop_time: float,
                       description: str, sources_only: bool) -> str:
    """Text of ``documentation/index.html``.

    Parameters
    ----------
    model : LinearModel
    model_identifier : str
    fmi_version : {"2.0", "3.0"}
    interfaces : tuple of {"me", "cs"}
    step, stop_time : float, s
        DefaultExperiment stepSize and stopTime.
    description : str
        The modelDescription's description.
    sources_only : bool
        Whether the FMU ships no binary.

    Returns
    -------
    str
    """
    n, m, p = model.n_states, model.n_inputs, model.n_outputs
    name = html.escape(model_identifier)
    units = variable_units(model)

    def unit(signal: str) -> str:
        text = units.get(signal)
        return html.escape(text) if text else "&ndash;"

    interface_names = " and ".join({"me": "Model Exchange", "cs": "Co-Simulation"}[i]
                                   for i in interfaces)
    parts = [f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
             f"<title>{name}</title><style>{_STYLE}</style></head><body>\n",
             f"<h1>{name}</h1>\n<p>{html.escape(description)}</p>\n"]
    if model.discrete:
        T = c_double(model.sample_period)
        parts.append(
            f"<h2>Model</h2>\n<p>A discrete-time linear time-invariant system sampled every "
            f"T = {T} s, from the start time t<sub>0</sub>:</p>\n"
            "<pre>x[k+1] = A x[k] + B u(t_k),   y(t) = C x[k] + D u(t_k)   for t_k &le; t &lt; "
            "t_k+1,   t_k = t_0 + k T</pre>\n"
            "<p>A sample takes the inputs as they are at t<sub>k</sub>; the outputs are then "
            "held until the next sample. At a sample instant whose sample is still to be "
            "taken, the outputs are C x[k] + D u with the inputs as set now (direct "
            "feedthrough). A co-simulation step of any length takes every sample instant "
            "inside it, with the inputs held: the FMU updates every T whatever the "
            "communication step.</p>\n")
        if fmi_version == "3.0":
            parts.append(
                "<p>FMI 3.0: the equations form the clocked partition of the periodic "
                "time-based input Clock <code>sample_clock</code> (interval T, first tick at "
                "the start time). An importer in Event Mode activates it at every tick "
                "(<code>fmi3SetClock</code>, then <code>fmi3UpdateDiscreteStates</code>); "
                "ticks that the importer does not activate (no Event Mode) are taken by "
                "<code>fmi3DoStep</code>, with the same result.</p>\n")
    else:
        parts.append(
            "<h2>Model</h2>\n<p>A continuous-time linear time-invariant system:</p>\n"
            "<pre>dx/dt = A x + B u,   y = C x + D u</pre>\n"
            "<p>Outputs are always computed from the current inputs (direct feedthrough is "
            "never stale). A co-simulation step of any length h is exact for inputs held "
            "over the step: x(t+h) = &Phi;(h) x(t) + &Gamma;(h) u with "
            "expm([[A, B], [0, 0]] h) = [[&Phi;, &Gamma;], [0, I]], precomputed for the "
            f"default step {c_double(step)} s and computed in the FMU (scaling and squaring, "
            "Pad&eacute; 13) for any other.</p>\n")
    parts.append(
        f"<p>FMI {fmi_version}, {interface_names}. FMU states can be saved, restored and "
        "serialised (bit-identical rollback); directional derivatives"
        f"{' and adjoint derivatives' if fmi_version == '3.0' else ''} are the entries of A, "
        "B, C, D (for a sampled model, D at a sample instant and 0 between samples). "
        f"Default experiment: 0 to {c_double(stop_time)} s, step {c_double(step)} s.</p>\n")
    parts.append(f"<h2>Variables ({m} inputs, {p} outputs, {n} states)</h2>\n"
                 "<table><tr><th class=\"name\">name</th><th class=\"name\">causality</th>"
                 "<th class=\"name\">unit</th><th>start</th><th>nominal</th></tr>\n")
    for signal in model.input_names:
        parts.append(f'<tr><td class="name">{html.escape(signal)}</td><td class="name">input'
                     f'</td><td class="name">{unit(signal)}</td><td>0.0</td><td></td></tr>\n')
    for signal in model.output_names:
        parts.append(f'<tr><td class="name">{html.escape(signal)}</td><td class="name">output'
                     f'</td><td class="name">{unit(signal)}</td><td></td><td></td></tr>\n')
    for j, signal in enumerate(model.state_names):
        parts.append(f'<tr><td class="name">{html.escape(signal)}</td><td class="name">state'
                     f'</td><td class="name">{unit(signal)}</td><td>{c_double(model.x0[j])}</td>'
                     f'<td>{c_double(model.nominals[j])}</td></tr>\n')
    parts.append("</table>\n<p>Nominals: the largest magnitude of each state over the "
                 "default experiment, from its initial state and from a unit step of each "
                 "input (two significant digits).</p>\n")
    parts.append("<h2>Matrices</h2>\n")
    entries = n * n + n * m + p * n + p * m
    if entries <= MAX_DOCUMENTED_ENTRIES:
        parts.append(_matrix("A", model.A, model.state_names, model.state_names))
        parts.append(_matrix("B", model.B, model.state_names, model.input_names))
        parts.append(_matrix("C", model.C, model.output_names, model.state_names))
        parts.append(_matrix("D", model.D, model.output_names, model.input_names))
        parts.append("<p>Numbers are the shortest decimals that read back as the exact "
                     "doubles the FMU computes with.</p>\n")
    else:
        parts.append(f"<p>{entries} entries: too many to list here. <code>sources/model.c"
                     "</code> holds A, B, C, D exactly (row-major, shortest round-trip "
                     "decimals).</p>\n")
    parts.append("<h2>Poles</h2>\n")
    parts.append(_poles(model))
    binary = ("This FMU ships sources only: compile <code>sources/</code> as "
              "<code>sources/buildDescription.xml</code> describes"
              if sources_only else
              "The binary needs only the C library and the C math library (glibc 2.17 or "
              "newer on Linux); <code>sources/</code> rebuilds it as "
              "<code>sources/buildDescription.xml</code> describes")
    headers = ("the FMI 2.0 headers are in <code>sources/</code>" if fmi_version == "2.0" else
               "the FMI 3.0 headers come from the importer (FMI 3.0.2, section 2.5.1.4)")
    parts.append(f"<h2>Building and dependencies</h2>\n<p>{binary}; {headers}. No other "
                 "external dependencies.</p>\n"
                 "<h2>Licences</h2>\n<p>See <code>documentation/licenses/license.txt</code>.</p>\n"
                 "<p>Generated by flexsat.fmu.</p>\n</body></html>\n")
    return "".join(parts)


def licence_text(fmi_version: str, header_licence: str) -> str:
    """Text of ``documentation/licenses/license.txt``: what the FMU contains and the licence
    of the FMI headers it was compiled against (their BSD licence asks binary
    redistributions to reproduce it)."""
    return ("Licences of the material in this FMU\n"
            "====================================\n\n"
            "The model code (sources/*.c, sources/*.h other than the FMI headers) and the "
            "binary were generated by flexsat.fmu from the user's model.\n\n"
            f"The binary was compiled against the FMI {fmi_version} standard headers of the "
            "Modelica Association, distributed under the following licence:\n\n"
            + header_licence)


# ---------------------------------------------------------------------------- the icon

_SIZE = 96


def _png(pixels: np.ndarray) -> bytes:
    """PNG bytes of an (height, width, 4) uint8 RGBA image (filter 0 on every row)."""
    height, width, _ = pixels.shape
    raw = b"".join(b"\x00" + pixels[row].tobytes() for row in range(height))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)  # 8-bit RGBA
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def icon_png(model: LinearModel) -> bytes:
    """A 96 x 96 icon: the block, its input and output arrows, a response inside."""
    image = np.zeros((_SIZE, _SIZE, 4), dtype=np.uint8)  # transparent
    ink = np.array([30, 60, 120, 255], dtype=np.uint8)
    fill = np.array([235, 242, 252, 255], dtype=np.uint8)
    left, right, top, bottom = 18, 78, 14, 82
    image[top:bottom, left:right] = fill
    image[top:top + 2, left:right] = ink
    image[bottom - 2:bottom, left:right] = ink
    image[top:bottom, left:left + 2] = ink
    image[top:bottom, right - 2:right] = ink

    def arrows(count: int, x_from: int, x_to: int) -> None:
        for k in range(min(count, 8)):
            y = top + (k + 1) * (bottom - top) // (min(count, 8) + 1)
            image[y - 1:y + 1, x_from:x_to] = ink
            for d in range(4):  # arrow head pointing right
                image[y - 1 - d:y + 1 + d, x_to - 1 - d] = ink

    arrows(model.n_inputs, 2, left)
    arrows(model.n_outputs, right, _SIZE - 2)
    # a step response inside: smooth (continuous time) or a staircase (sampled)
    width = right - left - 12
    previous = None
    for i in range(width):
        t = 6.0 * i / width
        value = 1.0 - math.exp(-0.6 * t) * math.cos(2.2 * t)
        if model.discrete:
            t_held = math.floor(t / 0.75) * 0.75
            value = 1.0 - math.exp(-0.6 * t_held) * math.cos(2.2 * t_held)
        y = int(round(bottom - 12 - value * (bottom - top - 30) / 1.6))
        x = left + 6 + i
        low, high = (y, y) if previous is None else (min(y, previous), max(y, previous))
        image[low - 1:high + 1, x] = ink
        previous = y
    return _png(image)
