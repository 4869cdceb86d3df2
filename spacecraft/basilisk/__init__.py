"""flexsat in Basilisk: a flexsat spacecraft's chains and controller as a Basilisk simulation.

Basilisk (the open-source astrodynamics framework, PyPI package ``bsk``) is optional: install the
extra ``flexsat[basilisk]``. Importing this package does not import Basilisk; the functions that
need it raise :class:`BasiliskNotInstalled` (one line: how to install the extra) without it.

- :func:`layout`: the spacecraft as Basilisk parameters (hub with rigidly mounted bodies folded
  in, one ``spinningBodyNDOFStateEffector`` per chain; three axes: two bending hinges and a
  torsion hinge per joint); no Basilisk needed. :func:`linearised`: Basilisk's model of it
  linearised about rest.
- :func:`flight_software_law`: any flexsat controller as the digital law Basilisk runs.
- :func:`simulate_slew`: the scene's slew in Basilisk; theta, omega, tip deflections and torque
  as flexsat's plant defines them (three axes: the eigen-axis slew, per axis).
  :func:`linear_slew`: flexsat's prediction of the same
  sampled-data loop; :func:`compare`: the differences; :func:`slew_comparison`: all of it in one
  call (Basilisk vs truth, vs linear chain, chain vs truth), for the runner and the report.
"""

from .actuators import ReactionWheel
from .comparison import SlewComparison, compare, linear_slew, slew_comparison
from .flight_software import (LOOP_GAIN_FLOOR, SAMPLES_PER_CROSSOVER, SIGNALS_3, TORQUES_3,
                              FlightSoftwareLaw, default_sample_time, flight_software_law,
                              rotation_vector)
from .install import (INSTALL_HINT, TESTED_VERSIONS, BasiliskIntegrationError,
                      BasiliskModelError, BasiliskModelWarning, BasiliskNotInstalled,
                      BasiliskRunTooLong, BasiliskVersionWarning, require_basilisk)
from .layout import (AppendageLayout, BodyLayout, HubLayout, SpacecraftLayout, basilisk_chain,
                     chain_spacecraft, inextensible, layout, torsion_frequency, torsion_held)
from .simulation import (DISTURBANCES_3, MAX_SECONDS, BasiliskResult, LinearisedModel,
                         dynamics_step, estimated_seconds, largest_stable_step, linearised,
                         simulate, simulate_slew, slew_reference)

__all__ = [
    "AppendageLayout", "BasiliskIntegrationError", "BasiliskModelError", "BasiliskModelWarning",
    "BasiliskNotInstalled", "BasiliskResult", "BasiliskRunTooLong", "BasiliskVersionWarning",
    "BodyLayout", "DISTURBANCES_3", "FlightSoftwareLaw", "HubLayout", "INSTALL_HINT",
    "LOOP_GAIN_FLOOR", "LinearisedModel", "MAX_SECONDS", "ReactionWheel",
    "SAMPLES_PER_CROSSOVER", "SIGNALS_3", "SlewComparison", "SpacecraftLayout", "TESTED_VERSIONS",
    "TORQUES_3", "basilisk_chain",
    "chain_spacecraft", "compare", "default_sample_time", "dynamics_step", "estimated_seconds",
    "flight_software_law", "inextensible", "largest_stable_step", "layout", "linear_slew",
    "linearised", "require_basilisk", "rotation_vector", "simulate", "simulate_slew",
    "slew_comparison", "slew_reference", "torsion_frequency", "torsion_held",
]
