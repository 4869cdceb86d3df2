"""flexsat controllers: PD and LQR attitude controllers for any plant with named signals.

Works on any python-control LTI plant with input ``'torque'`` and outputs ``'theta'``,
``'omega'`` (optionally ``'*tip_deflection'``), or with the three-axis signals ``'torque_x'``,
``'torque_y'``, ``'torque_z'``, ``'theta_x'``..``'theta_z'``, ``'omega_x'``..``'omega_z'``
(:mod:`controllers.signals`): one set of functions for both; imports no other flexsat package.
"""
from .frequency import frequency_response_data
from .loop import close_loop, loop_frequency_response
from .margins import (Margins, ModeSpillover, MultiLoopMargins, SpilloverVerdict, loop_margins,
                      margins, nyquist_count, spillover)
from .modes import INFLUENCE_TOL, FlexibleMode, flexible_modes, rigid_body_inertia
from .timeresp import (METRIC_UNITS, disturbance_response, manoeuvre_metrics, metrics,
                       profile_response, slew, slew_profile, step_response)
from .compare import Comparison, compare
from .delay import PLAUSIBLE_DELAY, LongDelayWarning
from .discretise import DiscretisationOverflowWarning
from .lqr import (KalmanNoise, LQRDesign, lqr, lqr_design, rate_reference_state,
                  reference_state)
from .noise import LargeNoiseWarning, SensorNoise
from .pd import natural_frequency_from_bandwidth, pd, pd_gains, principal_axes
from .pointing import PointingBudget, close_loop_with_sensors, pointing
from .profiles import (PROFILE_KINDS, Profile, Shaper, bang_coast_bang, jerk_limited,
                       minimum_time, mode_shaper, reference_profile, shaped, step_reference,
                       zv_shaper, zvd_shaper)
from .simulate import Simulator, simulate
from .stability import MARGIN, RemovedMode, RemovedModesWarning
from .testing import assert_closed_loops_close, compare_metrics
from .wheel_loop import WheelLoop, WheelResponse, simulate_wheels
from .wheels import ReactionWheel, WheelSet, check_slew_time, shortest_slew_time

__all__ = [
    "Comparison",
    "DiscretisationOverflowWarning",
    "INFLUENCE_TOL",
    "LongDelayWarning",
    "LargeNoiseWarning",
    "MARGIN",
    "RemovedMode",
    "ReactionWheel",
    "RemovedModesWarning",
    "PointingBudget",
    "SensorNoise",
    "FlexibleMode",
    "KalmanNoise",
    "LQRDesign",
    "METRIC_UNITS",
    "PLAUSIBLE_DELAY",
    "PROFILE_KINDS",
    "Profile",
    "Shaper",
    "Margins",
    "ModeSpillover",
    "MultiLoopMargins",
    "Simulator",
    "SpilloverVerdict",
    "WheelLoop",
    "WheelResponse",
    "WheelSet",
    "assert_closed_loops_close",
    "bang_coast_bang",
    "check_slew_time",
    "close_loop",
    "close_loop_with_sensors",
    "compare",
    "compare_metrics",
    "disturbance_response",
    "flexible_modes",
    "frequency_response_data",
    "jerk_limited",
    "loop_frequency_response",
    "loop_margins",
    "lqr",
    "lqr_design",
    "manoeuvre_metrics",
    "margins",
    "nyquist_count",
    "metrics",
    "minimum_time",
    "mode_shaper",
    "natural_frequency_from_bandwidth",
    "pd",
    "pd_gains",
    "pointing",
    "principal_axes",
    "profile_response",
    "rate_reference_state",
    "reference_profile",
    "reference_state",
    "rigid_body_inertia",
    "shaped",
    "shortest_slew_time",
    "simulate",
    "simulate_wheels",
    "slew",
    "slew_profile",
    "spillover",
    "step_reference",
    "step_response",
    "zv_shaper",
    "zvd_shaper",
]
