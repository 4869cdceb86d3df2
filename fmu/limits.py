"""Limits of the fmu package: the work an export or a co-simulation may take on.

Every entry point estimates its work from its arguments before doing any of it, and refuses
at once, naming the limit, what exceeds it. The limits are module constants, read at each
call: raise one for a whole session with e.g. ``fmu.limits.MAX_STATES = 3000`` (the
reference-file limit also has a keyword, ``fmu.export(..., max_reference_samples=...)``).

Why these values (2-core, 24 GiB machines; figures measured there or counted from the
code):

- :data:`MAX_STATES` = 1000 states. The cost of an export grows with n^2 (model.c holds
  A and Phi as decimal literals, 2 n^2 numbers of up to 24 characters: 44 MB at n = 1000
  for dense matrices; modelDescription.xml lists up to n^2 dependencies) and inside the
  FMU with n^3 (a Co-Simulation step of a new size computes a matrix exponential of order
  n + m, about 30 (n + m)^3 flops, and each instance holds a workspace of 9 (n + m)^2
  doubles, 72 MB at n = 1000). Measured: a 1000-state modal plant (block diagonal, 11 MB
  of model.c) exported in 19 s on the 2-core machine at load 9. Flexible spacecraft
  models in flexsat have tens to a few hundred states.
- :data:`MAX_SIGNALS` = 1000 inputs plus outputs: B, C and D grow with n times the number
  of signals, and every signal is an FMU variable that importing tools list and connect.
- :data:`MAX_REFERENCE_SAMPLES` = 10^6 samples of the reference files (stop_time / step):
  the reference response is simulated sample by sample and kept in memory (n + m + p
  doubles per sample plus a Python row), and ``<model>_ref.csv`` holds about 24 bytes per
  value, 72 MB for two outputs at 10^6 samples, which cross-check tools read whole. A
  reference for FMI cross-checking is a short run; 10^6 samples are 1000 s at 1 ms.
- :data:`MAX_REFERENCE_MEMORY` = 4 GiB, the estimated peak memory of the reference
  simulation (see :func:`reference_cost`), so that a large model cannot reach a
  sixth of the machine's memory even within the sample limit.
- :data:`MAX_DESCRIPTION_LENGTH` = 4096 characters of ``description``, the attribute of
  modelDescription.xml that importing tools show beside the model (the scene's limit on its
  title, ``limits.string_length``, is the same): an attribute, not a document.
- :data:`MAX_MODEL_NAME_LENGTH` = 200 characters of ``model_name``: it names files,
  ``<model_name>.so`` in the FMU and ``<model_name>_ref.csv`` beside it, and a file name has
  at most 255 bytes on Linux, macOS and Windows file systems.
- :data:`MAX_COSIMULATION_STEPS` = 10^7 communication steps of :func:`fmu.cosimulate`:
  each step is a handful of FMU calls through ctypes (2 * 10^4 steps per second measured
  for a 4-state plant and a PD controller), so 10^7 steps take about 10 minutes, and the
  result holds a row of float64 per step (400 MB for that pair's 5 columns).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["MAX_STATES", "MAX_SIGNALS", "MAX_REFERENCE_SAMPLES", "MAX_REFERENCE_MEMORY",
           "MAX_COSIMULATION_STEPS", "MAX_DESCRIPTION_LENGTH", "MAX_MODEL_NAME_LENGTH",
           "ReferenceCost", "reference_cost", "check_model_size", "check_reference_cost",
           "check_cosimulation_steps", "check_length"]

#: Most states an exported system may have.
MAX_STATES = 1000
#: Most inputs plus outputs an exported system may have.
MAX_SIGNALS = 1000
#: Most samples (stop_time / step + 1) of the reference files written by ``reference=True``.
MAX_REFERENCE_SAMPLES = 1_000_000
#: Most memory the reference simulation may be estimated to need [bytes].
MAX_REFERENCE_MEMORY = 4 * 2**30
#: Most communication steps of one co-simulation.
MAX_COSIMULATION_STEPS = 10_000_000
#: Most characters of an FMU's description.
MAX_DESCRIPTION_LENGTH = 4096
#: Most characters of an FMU's model_name (a file name, with suffixes, within 255 bytes).
MAX_MODEL_NAME_LENGTH = 200

# Estimated bytes per value written to a CSV file: repr of a double is at most 24
# characters ("-1.2345678901234567e-300") plus the comma.
_CSV_BYTES_PER_VALUE = 25


@dataclass(frozen=True)
class ReferenceCost:
    """Estimated cost of the reference files of an export.

    Attributes
    ----------
    samples : float
        Grid points ``round(stop_time / step) + 1`` (a float: it may exceed any int64).
    memory_bytes : float
        Peak memory of the simulation and of writing the files [bytes] (an estimate).
    file_bytes : float
        Size of ``<model>_ref.csv`` [bytes] (an upper estimate; the other two files are a
        few lines).
    """

    samples: float
    memory_bytes: float
    file_bytes: float


def _size(n_bytes: float) -> str:
    for unit, scale in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes:.0f} B"


def reference_cost(n_states: int, n_inputs: int, n_outputs: int, step: float,
                   stop_time: float) -> ReferenceCost:
    """Estimate the samples, memory and file size of the reference files.

    The reference response (:func:`fmu.reference.reference_response`) holds per sample the
    states, inputs (twice) and outputs as float64 and then each output row as a small
    NumPy array (about 100 bytes of overhead) and as Python floats while it is written
    (about 32 bytes a value plus about 24 characters of text).

    Parameters
    ----------
    n_states, n_inputs, n_outputs : int
    step, stop_time : float, s
        Positive and finite.

    Returns
    -------
    ReferenceCost
    """
    ratio = stop_time / step
    samples = math.floor(ratio + 0.5) + 1.0 if math.isfinite(ratio) else math.inf
    columns = 1 + n_outputs
    per_sample = 8.0 * (n_states + 2 * n_inputs + n_outputs + 1) + 100.0 + 8.0 * columns \
        + (32.0 + _CSV_BYTES_PER_VALUE) * columns
    return ReferenceCost(samples=samples, memory_bytes=samples * per_sample,
                         file_bytes=samples * columns * _CSV_BYTES_PER_VALUE)


def check_model_size(n_states: int, n_inputs: int, n_outputs: int) -> None:
    """Refuse a system with more than :data:`MAX_STATES` states or :data:`MAX_SIGNALS` signals.

    Raises
    ------
    ValueError
        Naming the limit and how to raise it.
    """
    if n_states > MAX_STATES:
        raise ValueError(
            f"system must have at most fmu.limits.MAX_STATES = {MAX_STATES} states; got "
            f"{n_states}. Reduce the model (fewer modes, a balanced truncation) or raise "
            "fmu.limits.MAX_STATES if the machine can take it (see fmu.limits for the costs).")
    if n_inputs + n_outputs > MAX_SIGNALS:
        raise ValueError(
            f"system must have at most fmu.limits.MAX_SIGNALS = {MAX_SIGNALS} inputs plus "
            f"outputs; got {n_inputs} + {n_outputs}. Export fewer signals or raise "
            "fmu.limits.MAX_SIGNALS.")


def check_length(name: str, text: str, limit_name: str) -> str:
    """``text`` if it has at most ``fmu.limits.<limit_name>`` characters, else ValueError
    naming ``name``, the limit, the length and the text's first characters."""
    limit = globals()[limit_name]
    if len(text) > limit:
        raise ValueError(f"{name} must have at most fmu.limits.{limit_name} = {limit} "
                         f"characters; got {len(text)} ({text[:40]!r}...)")
    return text


def check_reference_cost(cost: ReferenceCost, step: float, stop_time: float,
                         max_samples: float) -> None:
    """Refuse reference files beyond ``max_samples`` or :data:`MAX_REFERENCE_MEMORY`.

    Raises
    ------
    ValueError
        Naming stop_time and step, the estimated samples, memory and file size, the limit
        and how to raise it.
    """
    what = (f"reference files for stop_time / step = {stop_time!r} s / {step!r} s need "
            f"{cost.samples:.4g} samples (about {_size(cost.memory_bytes)} of memory and "
            f"{_size(cost.file_bytes)} of CSV)")
    if cost.samples > max_samples:
        raise ValueError(
            f"{what}; expected at most max_reference_samples = {max_samples:.4g} "
            f"(default fmu.limits.MAX_REFERENCE_SAMPLES). Choose a longer step or a shorter "
            "stop_time, pass reference=False, or raise max_reference_samples.")
    if cost.memory_bytes > MAX_REFERENCE_MEMORY:
        raise ValueError(
            f"{what}; expected at most fmu.limits.MAX_REFERENCE_MEMORY = "
            f"{_size(MAX_REFERENCE_MEMORY)} of memory. Choose a longer step or a shorter "
            "stop_time, pass reference=False, or raise fmu.limits.MAX_REFERENCE_MEMORY.")


def check_cosimulation_steps(n_steps: float, step: float, duration: float) -> None:
    """Refuse a co-simulation of more than :data:`MAX_COSIMULATION_STEPS` steps.

    Raises
    ------
    ValueError
    """
    if n_steps > MAX_COSIMULATION_STEPS:
        raise ValueError(
            f"stop_time - start_time must be at most fmu.limits.MAX_COSIMULATION_STEPS = "
            f"{MAX_COSIMULATION_STEPS:.4g} steps of {step!r} s; got {duration!r} s = "
            f"{n_steps:.4g} steps. Choose a longer step or a shorter time, or raise "
            "fmu.limits.MAX_COSIMULATION_STEPS.")
