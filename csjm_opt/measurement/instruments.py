"""Instrument uncertainties of the paper (Tables 1-2) as standard deviations.

Table 1 (laser tracker): expanded uncertainty ``U = 15 um + 6 um/m * d`` for a
point at distance ``d``; read here as a 95 % (k = 2) bound, so ``sigma = U / 2``.
Table 2 (F/T sensor): 95 % uncertainty in percent of full scale; ``sigma =
U / 1.96``. Orientation noise of {A} follows from point noise over the lever
arm of the tracked targets: ``sigma_angle ~ sqrt(2) sigma_point / arm``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

#: Table 2: full scale and 95 % uncertainty (fraction of full scale).
FT_FULL_SCALE = {"fx": 145.0, "fy": 145.0, "fz": 290.0, "tx": 5.0, "ty": 5.0, "tz": 5.0}
FT_U95_FRACTION = {"fx": 0.0125, "fy": 0.0100, "fz": 0.0075, "tx": 0.0125, "ty": 0.0150, "tz": 0.0125}
#: Table 1: tracker uncertainty U = TRACKER_U0_M + TRACKER_U_PER_M * distance.
TRACKER_U0_M = 15e-6
TRACKER_U_PER_M = 6e-6


@dataclasses.dataclass(frozen=True)
class InstrumentNoise:
    """Standard deviations of the measured moment (N m, per axis) and orientation (rad)."""

    tau_sigma_Nm: tuple[float, float, float]
    angle_sigma_rad: float

    @classmethod
    def paper(cls, tracker_distance_m: float = 3.0, target_arm_m: float = 0.1) -> "InstrumentNoise":
        """Noise of the paper's instruments (Tables 1-2): the F/T sensor and the laser tracker.

        Parameters
        ----------
        tracker_distance_m : float, optional
            Distance of the tracker from the targets (m); its point uncertainty grows with it.
        target_arm_m : float, optional
            Distance between the tracked targets on the platform (m); orientation noise is the point
            noise over this arm.

        Returns
        -------
        InstrumentNoise
            Moment standard deviation per axis (N m) and orientation standard deviation (rad).
        """
        tx, ty, tz = (FT_U95_FRACTION[a] * FT_FULL_SCALE[a] / 1.96 for a in ("tx", "ty", "tz"))
        tau = (tx, ty, tz)
        point_sigma = (TRACKER_U0_M + TRACKER_U_PER_M * tracker_distance_m) / 2
        return cls(tau, float(np.sqrt(2) * point_sigma / target_arm_m))

    @classmethod
    def none(cls) -> "InstrumentNoise":
        """No noise (for noise-free simulations).

        Returns
        -------
        InstrumentNoise
            Zero moment and orientation standard deviations.
        """
        return cls((0.0, 0.0, 0.0), 0.0)

    def tracker_point_sigma_m(self, distance_m: float) -> float:
        """Standard deviation of one tracked point at a distance: half the uncertainty ``U0 + U1 d`` of Table 1.

        Parameters
        ----------
        distance_m : float
            Distance from the tracker (m).

        Returns
        -------
        float
            Standard deviation (m).
        """
        return (TRACKER_U0_M + TRACKER_U_PER_M * distance_m) / 2

    def sample(self, tau_A_Nm: np.ndarray, R: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Noisy readings of true moments and orientations: Gaussian per moment axis, isotropic body-frame angle.

        The moment noise is drawn first, then the angle noise (one ``(n, 3)`` draw each), so a
        seeded generator gives the same readings wherever this is called.

        Parameters
        ----------
        tau_A_Nm : (n, 3) array
            Moments the F/T sensor would read without noise (N m, in {A}).
        R : (n, 3, 3) array
            Orientations the tracker would report without noise.
        rng : numpy.random.Generator
            Source of the noise.

        Returns
        -------
        tau_meas_A_Nm : (n, 3) array
            ``tau + e``, ``e ~ N(0, diag(tau_sigma_Nm^2))``.
        R_meas : (n, 3, 3) array
            ``R exp(hat(w))``, ``w ~ N(0, angle_sigma_rad^2 I)``.
        """
        from .. import so3

        tau_meas = tau_A_Nm + rng.normal(size=np.shape(tau_A_Nm)) * np.asarray(self.tau_sigma_Nm)
        R_meas = R @ so3.exp(rng.normal(size=(len(R), 3)) * self.angle_sigma_rad)
        return tau_meas, R_meas
