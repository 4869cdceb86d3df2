"""One name and one colour per thing, everywhere: summary, tables, plots, results.json.

The design models are named by how they were obtained (``design_label``: "chain, flexsat fit",
"chain, paper's fit", "design model"); the loops by the controller and the model they are
closed on ("PD tuned on chain, flexsat fit", closed on the design model or on the truth model);
each design model has one colour in every plot, the truth-model loop a solid line and the
design-model loop a dashed one, the exact distributed beam black, Basilisk dotted, anything
unstable red.
"""

from __future__ import annotations

__all__ = ["FIT_LABELS", "design_label", "controller_label", "loop_label", "variant_colour",
           "UNSTABLE_COLOUR", "CAUTION_COLOUR", "EXACT_COLOUR", "REFERENCE_COLOUR", "TRUTH_STYLE", "DESIGN_STYLE",
           "BASILISK_STYLE", "BASILISK_COLOUR", "MOTION_WORDS", "plural"]

#: A three-axis beam's motions in words, by the keys of a truncation's modes per motion
#: (:attr:`appendages.ModalBeam.modes_per_motion`).
MOTION_WORDS = {"xy": "bending in x-y", "xz": "bending in x-z", "torsion": "torsion",
                "axial": "axial motion"}

#: Names of the design models by fit criterion (and of a scene's own design model).
FIT_LABELS = {"poles-and-zeros": "chain, flexsat fit", "frequencies": "chain, paper's fit",
              "design": "design model"}

# matplotlib's default cycle (tab10) without its red, kept for what is unstable
_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf")
_VARIANT_ORDER = ("poles-and-zeros", "frequencies", "design")

#: Colour of anything unstable (a diverging response, an unstable pole, an UNSTABLE verdict).
UNSTABLE_COLOUR = "#d62728"
#: Colour of a caution on a stable loop (low margins, light or lowered damping): the report's
#: orange.
CAUTION_COLOUR = "#a04800"
#: Colour of the exact distributed beam.
EXACT_COLOUR = "black"
#: Colour of Basilisk's curves (dotted, BASILISK_STYLE).
BASILISK_COLOUR = "#222222"
#: Colour of the reference theta_ref and of guide lines.
REFERENCE_COLOUR = "0.45"
#: Line styles: loop closed on the truth model, on the design model, Basilisk's run.
TRUTH_STYLE, DESIGN_STYLE, BASILISK_STYLE = "-", "--", ":"


def design_label(variant: str) -> str:
    """Display name of a design variant (a fit criterion, or ``"design"``)."""
    return FIT_LABELS.get(variant, variant)


def controller_label(kind: str) -> str:
    """``"PD"``, ``"LQR"``."""
    return kind.upper()


def loop_label(variant: str, kind: str, which: str) -> str:
    """E.g. ``"PD tuned on chain, flexsat fit, closed on the truth model"``."""
    return (f"{controller_label(kind)} tuned on {design_label(variant)}, closed on the "
            f"{which} model")


def variant_colour(variant: str) -> str:
    """The colour of a design variant in every plot."""
    k = _VARIANT_ORDER.index(variant) if variant in _VARIANT_ORDER[:2] else (
        0 if variant == "design" else 2 + sum(map(ord, variant)) % (len(_COLOURS) - 2))
    return _COLOURS[k]


def plural(n: int, word: str, words: str | None = None) -> str:
    """``"1 bending mode"``, ``"2 bending modes"``."""
    return f"{n} {word if n == 1 else (words or word + 's')}"
