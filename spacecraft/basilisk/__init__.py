"""flexsat in Basilisk: a flexsat spacecraft's chains and controller as a Basilisk simulation.

Basilisk (the open-source astrodynamics framework, PyPI package ``bsk``) is optional: install the
extra ``flexsat[basilisk]``. Importing this package does not import Basilisk; the functions that
need it raise :class:`BasiliskNotInstalled` (one line: how to install the extra) without it.

- :func:`layout`: the spacecraft as Basilisk parameters (hub with rigidly mounted bodies folded
  in, one ``spinningBodyNDOFStateEffector`` per chain); no Basilisk needed.
- :func:`flight_software_law`: any flexsat controller as the digital law Basilisk runs.
- :func:`simulate_slew`: the scene's slew in Basilisk; theta, omega, tip deflections and torque
  as flexsat's plant defines them. :func:`linear_slew`: flexsat's prediction of the same
  sampled-data loop; :func:`compare`: the differences; :func:`slew_comparison`: all of it in one
  call (Basilisk vs truth, vs linear chain, chain vs truth), for the runner and the report.
"""

from .actuators import ReactionWheel
from .comparison import SlewComparison, compare, linear_slew, slew_comparison
from .flight_software import (SAMPLES_PER_CROSSOVER, FlightSoftwareLaw, default_sample_time,
                              flight_software_law)
from .install import (INSTALL_HINT, TESTED_VERSIONS, BasiliskIntegrationError,
                      BasiliskModelError, BasiliskNotInstalled, BasiliskRunTooLong,
                      BasiliskVersionWarning,
                      require_basilisk)
from .layout import (AppendageLayout, BodyLayout, HubLayout, SpacecraftLayout, chain_spacecraft,
                     layout)
from .simulation import (MAX_SECONDS, BasiliskResult, dynamics_step, estimated_seconds, simulate,
                         simulate_slew)

__all__ = [
    "AppendageLayout", "BasiliskIntegrationError", "BasiliskModelError", "BasiliskNotInstalled",
    "BasiliskResult", "BasiliskRunTooLong", "BasiliskVersionWarning", "BodyLayout", "FlightSoftwareLaw", "HubLayout",
    "INSTALL_HINT", "MAX_SECONDS", "ReactionWheel", "SAMPLES_PER_CROSSOVER", "SlewComparison",
    "SpacecraftLayout", "TESTED_VERSIONS", "chain_spacecraft", "compare", "default_sample_time", "dynamics_step", "estimated_seconds",
    "flight_software_law", "layout", "linear_slew", "require_basilisk", "simulate",
    "simulate_slew", "slew_comparison",
]
