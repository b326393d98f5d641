"""Stiffness identification at a pose from measured loads and displacements (Section III).

For one load cycle (rows in time order, the first row is the reference)::

    dzeta_i = log(R_ref^T R_i)                        body frame, (46)
    tau_load_i = tau_ext_i + tau_weight(R_i)          total load (55)-(56), in {A}
    K_D ~ dtau_load / dzeta                           (48a), estimated by (49)
    K = K_D + K_L,  K_L = -1/2 hat(tau_load_ref)      (47), corrected (errata 1-2)

The default estimate is ``K_ml`` (``StiffnessEstimate.estimator``): maximum likelihood with
the tracker and F/T noise and the curvature of the moment-rotation relation from the rig model,
with the Cramér-Rao bound of its six entries (:mod:`csjm_opt.identification.ml_estimator`,
:mod:`csjm_opt.identification.cramer_rao`). For comparison, three more estimates are returned
together in :class:`StiffnessEstimate`:

* ``K_D_paper`` / ``K_paper``: the paper's literal ``Psi Omega^+`` on
  differences to the reference row (49)-(50), with the corrected ``K_L``.
* ``K_D`` / ``K``: affine least squares ``tau_load_i = c + K_D dzeta_i
  [+ terms of degree 2..order]`` over all rows, so the reference row's noise
  is not copied into every difference; ``K_L`` uses the fitted ``c``. With an
  :class:`~csjm_opt.measurement.instruments.InstrumentNoise`, the normal matrix is
  corrected for the known orientation noise in ``dzeta`` (errors-in-variables,
  corrected least squares) and the covariance uses the instrument model.
* ``K_sym``: the symmetric-constrained estimate. K is symmetric (37), so
  ``K_D - K_D^T = hat(tau0)`` with ``tau0`` the load at the reference; with
  ``K_D = S + 1/2 hat(tau0)`` the model ``tau_load_i = (I - 1/2 hat(dzeta_i))
  tau0 + S dzeta_i`` is linear in ``(tau0, S)`` and ``K_sym = S`` is fitted by
  generalised least squares, weighted by the row covariance
  ``Sigma_tau + sigma_angle^2 K_D K_D^T`` (effective variance).

Confidence intervals are analytic (Student t on the residual covariance, or
normal on the instrument covariance) and optionally a pairs bootstrap.

Refusal rule (what cannot be identified is not returned): a cycle is refused
with :class:`~csjm_opt.errors.IllConditionedData` when its displacements do
not span three directions (rank < 3 or condition > ``max_condition``), or when
the estimate is not determined to :data:`MAX_RELATIVE_HALF_WIDTH`: the largest
confidence half-width of any entry of K, relative to ``||K||_2`` (the largest
singular value of K), exceeds 0.2. The error carries ``direction``, the
weakest direction of the centred load moments in {A} (smallest right singular
vector): loads with a moment component along it supply what is missing.
``allow_ill_conditioned=True`` returns the estimate anyway (rank 3 needed),
marked ``ill_conditioned``.
"""

# The code lives in excitation, estimate, identify_pose and log_identification; these names
# stay importable from here.
from .estimate import StiffnessEstimate
from .identify_pose import identify_stiffness
from .log_identification import identify_cycles, identify_log
from .refusal import (
    MAX_CONDITION,
    MAX_RELATIVE_HALF_WIDTH,
    NOISE_FLOOR_FACTOR,
    excitation,
    weakest_load_direction,
)

__all__ = ["MAX_CONDITION", "MAX_RELATIVE_HALF_WIDTH", "NOISE_FLOOR_FACTOR", "StiffnessEstimate",
           "excitation", "identify_cycles", "identify_log", "identify_stiffness", "weakest_load_direction"]
