r"""Sensor noise: the attitude sensor's angle noise and the gyro's rate noise and bias.

The attitude loop measures theta (a star tracker) and omega (a gyro). Their errors, per axis:

- attitude sensor: white angle noise v, E[v(t) v(s)] = q^2 delta(t - s), q the
  ``attitude_density`` [rad/sqrt(Hz)]. A sensor quoted as an rms sigma per sample at a rate
  f_s [Hz] (its output the mean over its 1/f_s integration) has q = sigma / sqrt(f_s)
  (:meth:`SensorNoise.from_rms`): the mean of v over T has variance q^2 / T.
- gyro rate noise: white, E[n(t) n(s)] = N^2 delta(t - s), N the ``angle_random_walk``
  [rad/sqrt(s)]: the integrated rate error (the angle) random-walks with variance N^2 t, the
  IEEE Std 952 definition (Allan variance N^2 / tau) [1]_.
- gyro bias instability: a first-order Gauss-Markov bias b' = -b / tau_b + w with stationary
  standard deviation sigma_b (``bias_instability`` [rad/s]) and correlation time tau_b
  (``bias_correlation_time`` [s]); w is white with E[w(t) w(s)] = (2 sigma_b^2 / tau_b)
  delta(t - s), i.e. the driving density sqrt(2 / tau_b) sigma_b [rad/s^(3/2)] [2]_. (The
  Gauss-Markov form is the one with a stationary pointing error; a pure rate random walk has
  none: the error of a loop fed by it grows without bound.)

Densities are square roots of two-sided intensities (the delta-correlated forms above); a
datasheet's one-sided amplitude spectral density a [unit/sqrt(Hz)] of a white noise is
sqrt(2) q. Sampled every T (a digital controller), each noise's sample is what the sensor
gives for that interval: the angle noise and the rate noise have variances q^2 / T and N^2 / T
(the means over T), the bias the exact discretisation b_(k+1) = e^(-T / tau_b) b_k + w_k,
Var(w_k) = sigma_b^2 (1 - e^(-2 T / tau_b)) [2]_.

References
----------
.. [1] IEEE Std 952-1997, *IEEE Standard Specification Format Guide and Test Procedure for
   Single-Axis Interferometric Fiber Optic Gyros*, annex C (angle random walk, Allan variance).
.. [2] F. L. Markley, J. L. Crassidis, *Fundamentals of Spacecraft Attitude Determination and
   Control*, Springer, 2014, sec. 6.2 (gyro models) and sec. 3.7 (Gauss-Markov processes).
"""
from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np

from .arguments import describe, positive, real_number

__all__ = ["SensorNoise", "PLAUSIBLE", "LargeNoiseWarning"]

#: Values above these look like a unit slip (a warning names the likely unit): attitude noise
#: density [rad/sqrt(Hz)] (a star tracker: 1e-6 to 1e-4), angle random walk [rad/sqrt(s)]
#: (gyros: 1e-8 to 1e-4; deg/sqrt(h) given unconverted), bias instability [rad/s] (gyros: 1e-9
#: to 1e-5; deg/h given unconverted).
PLAUSIBLE = {"attitude_density": (1e-2, "arcsec/sqrt(Hz) or deg/sqrt(Hz)"),
             "angle_random_walk": (1e-3, "deg/sqrt(h) or deg/sqrt(s)"),
             "bias_instability": (1e-3, "deg/h or deg/s")}

class LargeNoiseWarning(UserWarning):
    """A sensor noise level above :data:`PLAUSIBLE`: legal, and used as given, but more likely
    a level in the data sheet's unit (arcsec, deg, hours) given unconverted (the message names
    the parameter, its value and the likely units)."""


_UNITS = {"attitude_density": "rad/sqrt(Hz)", "angle_random_walk": "rad/sqrt(s)",
          "bias_instability": "rad/s", "bias_correlation_time": "s"}


def _level(value, name: str) -> float | tuple[float, ...]:
    """A non-negative finite level, or a sequence of three (per axis)."""
    unit = _UNITS[name.split("[")[0]]
    if isinstance(value, (list, tuple, np.ndarray)):
        values = tuple(_level(v, f"{name}[{i}]") for i, v in enumerate(value))
        if len(values) != 3:
            raise ValueError(f"{name} must be one value or three (x, y, z) [{unit}]; got "
                             f"{len(values)}")
        return values
    x = real_number(value, name, unit)
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite [{unit}]; got {describe(value)}")
    if x < 0:
        raise ValueError(f"{name} must be non-negative [{unit}] (the square root of a noise "
                         f"intensity, a standard deviation); got {describe(value)}: a sign slip?")
    base = name.split("[")[0]
    if base in PLAUSIBLE and x > PLAUSIBLE[base][0]:
        warnings.warn(f"{name} = {x:.6g} {unit} is large for a spacecraft sensor: was it given "
                      f"in {PLAUSIBLE[base][1]}? The value is used as {unit}", LargeNoiseWarning,
                      stacklevel=4)
    return x


@dataclasses.dataclass(frozen=True)
class SensorNoise:
    """Noise of the attitude sensor and the gyro (see the module docstring for the models).

    Each level is one value (every axis) or three (x, y, z; three-axis loops).

    Parameters
    ----------
    attitude_density : float or 3 floats, rad/sqrt(Hz)
        q of the attitude sensor's white angle noise (square root of its two-sided intensity).
    angle_random_walk : float or 3 floats, rad/sqrt(s)
        N of the gyro's white rate noise.
    bias_instability : float or 3 floats, rad/s
        sigma_b, the stationary standard deviation of the gyro's Gauss-Markov bias.
    bias_correlation_time : float or 3 floats, s
        tau_b; required with a bias (and only then).

    Raises
    ------
    TypeError
        A level that is not a real number (a string with a unit: give SI numbers).
    ValueError
        A negative or non-finite level, a bias without its correlation time or a correlation
        time without a bias, a sequence of other than three values.

    Warns
    -----
    UserWarning
        A level beyond :data:`PLAUSIBLE` (a likely unit slip).
    """

    attitude_density: float | tuple = 0.0
    angle_random_walk: float | tuple = 0.0
    bias_instability: float | tuple = 0.0
    bias_correlation_time: float | tuple | None = None

    def __post_init__(self):
        for name in ("attitude_density", "angle_random_walk", "bias_instability"):
            object.__setattr__(self, name, _level(getattr(self, name), name))
        tau = self.bias_correlation_time
        has_bias = np.any(np.asarray(self.bias_instability) > 0)
        if tau is None:
            if has_bias:
                raise ValueError("bias_correlation_time [s] must be given with "
                                 "bias_instability (the Gauss-Markov bias's correlation time)")
            return
        if not has_bias:
            raise ValueError(f"bias_correlation_time = {describe(tau)} s is given without a "
                             "bias_instability [rad/s]: give both or neither")
        if isinstance(tau, (list, tuple, np.ndarray)):
            taus = tuple(positive(t, f"bias_correlation_time[{i}]", "s")
                         for i, t in enumerate(tau))
            if len(taus) != 3:
                raise ValueError(f"bias_correlation_time must be one value or three (x, y, z) "
                                 f"[s]; got {len(taus)}")
            object.__setattr__(self, "bias_correlation_time", taus)
        else:
            object.__setattr__(self, "bias_correlation_time",
                               positive(tau, "bias_correlation_time", "s"))

    @classmethod
    def from_rms(cls, attitude_rms: float, sample_rate: float, **kwargs) -> SensorNoise:
        """The noise of an attitude sensor quoted as an rms angle per sample at a rate.

        Parameters
        ----------
        attitude_rms : float, rad
            sigma, the standard deviation of one sample.
        sample_rate : float, Hz
            f_s, the sensor's rate (each sample the mean over 1/f_s).
        **kwargs
            The gyro's levels (see :class:`SensorNoise`).

        Returns
        -------
        SensorNoise
            With ``attitude_density`` = sigma / sqrt(f_s).
        """
        sigma = real_number(attitude_rms, "attitude_rms", "rad")
        if not (math.isfinite(sigma) and sigma >= 0):
            raise ValueError(f"attitude_rms must be non-negative and finite [rad]; got "
                             f"{describe(attitude_rms)}")
        rate = positive(sample_rate, "sample_rate", "Hz")
        return cls(attitude_density=sigma / math.sqrt(rate), **kwargs)

    def per_axis(self, n_axes: int) -> list[dict]:
        """The levels of each of ``n_axes`` axes (1 or 3) as floats: keys attitude_density,
        angle_random_walk, bias_instability, bias_correlation_time (None without a bias).

        Raises
        ------
        ValueError
            Three per-axis values for a planar loop.
        """
        if isinstance(n_axes, bool) or not isinstance(n_axes, (int, np.integer)) \
                or n_axes not in (1, 3):
            raise ValueError(f"n_axes must be 1 (planar) or 3; got {describe(n_axes)}")
        out = []
        for i in range(n_axes):
            axis = {}
            for name in ("attitude_density", "angle_random_walk", "bias_instability",
                         "bias_correlation_time"):
                value = getattr(self, name)
                if isinstance(value, tuple):
                    if n_axes != 3:
                        raise ValueError(f"{name} has three values (x, y, z) but the loop is "
                                         "planar: give one value")
                    value = value[i]
                axis[name] = value
            if axis["bias_instability"] == 0.0:
                axis["bias_correlation_time"] = None
            out.append(axis)
        return out
