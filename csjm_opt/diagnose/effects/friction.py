"""``friction``: Coulomb (capstan) friction of the cables at the base guide holes.

Where a cable slides through its guide hole, the tension on the platform side
is the drive-side tension ``T_d`` times ``exp(+mu_beta)`` when the cable is
drawn out towards the platform (its length ``c_i`` grows) and
``exp(-mu_beta)`` when it is pulled back; while it sticks, the ratio lies
inside that band. So ``T_p = T_d exp(mu_beta_i s_i)`` with a band position
``s_i in [-1, 1]`` that follows the cable's motion as a play (stop) operator::

    s_i[j] = clip(s_i[j-1] + dc_i[j] / travel_i[j], -1, 1),   s_i[first row] = 0
    travel_i = f mu_beta_i T_d,i / k_i

While a cable sticks, only its platform-side segment (a fraction ``rho`` of
the cable's compliance) stretches, so a length change ``dc`` moves ``T_p`` by
``k dc / rho``, and half the band is crossed after ``rho mu_beta T / k``.
The factor ``f >= 0`` (about ``rho``) is fitted (``f -> 0``: pure sliding,
``s = sign(dc)``). Path-dependent: the order of rows within a
cycle matters, and loading and unloading branches differ (hysteresis). The
length changes ``dc`` come from the measured poses when fitting, and from
the model's own predicted poses, row after row, when predicting held-out
cycles (:meth:`AugmentedModel.predict_poses`), so predictions need only
the log's inputs. A cycle's first row starts at a fitted band position ``s_0`` shared by all
cables (0: settled; -1: every cable last pulled in by its drive, as when the
drives have just tensioned the cables). Eight parameters
(``mu_beta_1..6 >= 0``, ``f >= 0``, ``-1 <= s_0 <= 1``).
"""

from __future__ import annotations

import numpy as np

from .base import Effect

#: Smallest stick travel (m): keeps the play operator continuous in the pose for
#: forward solves (a pure sign switch has no equilibrium at a reversal).
MIN_TRAVEL_M = 5e-6
#: Rounding of the band's edges (in units of the half band).
CORNER = 0.02


def _clip_band(s: np.ndarray) -> np.ndarray:
    """``clip(s, -1, 1)`` with corners rounded over ``CORNER`` (forward solves need continuity of slope)."""
    w = CORNER
    return -1.0 + w * np.logaddexp(0.0, (s + 1.0) / w) - w * np.logaddexp(0.0, (s - 1.0) / w)


def band_position(rows, travel_m: np.ndarray, s0: float = 0.0) -> np.ndarray:
    """``s`` (n, 6) of the play operator over each cycle's rows (``travel_m`` (n, 6) > 0)."""
    s = np.full_like(rows.cable_steps_m, s0)
    gain = 1.0 / travel_m
    for idx in rows.sequence:
        s[idx] = _clip_band(s[idx - 1] + rows.cable_steps_m[idx] * gain[idx])
    return s


class Friction(Effect):
    """Capstan factor ``mu_i beta_i`` of each guide hole and the stick travel (m)."""

    name = "friction"
    path_dependent = True
    description = ("capstan friction at guide holes: T_platform = T_drive exp(mu_beta_i s_i), "
                   "s_i a play operator of the cable's motion")

    @property
    def param_names(self):
        return tuple(f"mu_beta_{i + 1}" for i in range(6)) + ("stick_travel_factor", "first_row_state")

    @property
    def scales(self):
        return np.r_[np.full(6, 0.03), 0.5, 0.5]

    @property
    def lower_bounds(self):
        return np.r_[np.zeros(7), -1.0]

    @property
    def upper_bounds(self):
        return np.r_[np.full(7, np.inf), 1.0]

    def default_ranges(self):
        """Capstan factors up to 0.3 (35 % tension band: a badly worn guide), stick factor up to 2."""
        return {**{f"mu_beta_{i + 1}": (0.0, 0.3) for i in range(6)},
                "stick_travel_factor": (0.0, 2.0), "first_row_state": (-1.0, 1.0)}

    def x0(self) -> np.ndarray:
        return np.r_[np.zeros(6), 0.5, 0.0]

    def adjust_tension(self, ev, stretch_m, T_N, p):
        mu_beta, factor, s0 = p[:6], p[6], p[7]
        k = ev.cable_stiffness_N_per_m
        travel = np.maximum(factor * mu_beta * np.maximum(T_N, 1e-3) / k, MIN_TRAVEL_M)
        rows = ev.rows
        if rows.state_prev is None:                  # whole log at measured poses
            s = band_position(rows, travel, s0)
        else:                                        # one row per cycle, sequential prediction
            first = np.isnan(rows.lengths_prev_m)
            step = np.where(first, 0.0, ev.lengths_m - np.nan_to_num(rows.lengths_prev_m))
            s = np.where(first, s0, _clip_band(rows.state_prev + step / travel))
        ev.state_out = s
        return T_N * np.exp(s * mu_beta)

    def describe(self, p):
        return {"tension_band_percent": (100 * (np.exp(np.asarray(p[:6])) - 1)).tolist()}
