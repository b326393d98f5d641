"""Per-row residuals of the nominal model against a measurement log.

For row ``i`` the nominal model (rig file as given) predicts the pose of the
platform for the row's rest lengths and measured load (the measured moment,
fixed in {A}, plus the platform weight) by forward statics; the pose residual
is ``zeta_i = log(R_pred^T R_meas)`` (rad, in {A}). The moment residual is the
balance ``g = J^T T + tau_ext + tau_w`` evaluated at the *measured* pose (N m):
what the cables and load fail to balance where the platform really is.

The table also carries what the fits need: the tangent ``G = dg/dzeta`` at
the measured pose (``G ~ -K``), per-row whitening of the linearised pose
pose residual under instrument noise (moment noise through ``G^-1``, plus tracker noise), and the length change of each
cable from row to row within each cycle at the measured poses (friction fits).
Everything here uses only the log's inputs and the rig file.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ... import so3
from ...measurement.instruments import InstrumentNoise
from ...measurement.logfile import MeasurementLog
from ...model import kinematics as kin
from ...model.rig import Rig
from ..fitting.augmented import AugmentedModel, Rows, cable_steps, log_steps


@dataclasses.dataclass(frozen=True, eq=False)
class ResidualTable:
    """Nominal-model residuals of a log, row by row."""

    cycle: np.ndarray             # (n,)
    rows: Rows
    R_meas: np.ndarray            # (n, 3, 3)
    R_pred: np.ndarray            # (n, 3, 3) nominal forward statics
    converged: np.ndarray         # (n,) bool
    zeta_rad: np.ndarray          # (n, 3) log(R_pred^T R_meas), {A}
    moment_residual_Nm: np.ndarray  # (n, 3) g at R_meas
    G: np.ndarray                 # (n, 3, 3) dg/dzeta at R_meas (nominal)
    whiten: np.ndarray            # (n, 3, 3) W with W zeta ~ N(0, I) under instrument noise
    branch: np.ndarray            # (n,) +1 loading, -1 unloading, 0 first row of a cycle
    tau_weight_A_Nm: np.ndarray   # (n, 3) nominal weight moment at R_meas
    noise: InstrumentNoise        # the instrument model behind ``whiten``

    def __len__(self) -> int:
        return len(self.cycle)

    @property
    def rms_rad(self) -> float:
        """RMS pose residual of the table.

        Returns
        -------
        float
            ``sqrt(mean ||zeta_i||^2)`` (rad).
        """
        return rms(self.zeta_rad)

    @property
    def instrument_floor_rad(self) -> float:
        """RMS pose residual the instrument noise alone would give: ``sqrt(mean tr Cov_zeta)``."""
        return float(np.sqrt(np.mean(row_pose_noise_rad(self) ** 2)))

    @property
    def tilt_rad(self) -> np.ndarray:
        """Angle between the platform z axis and the base z axis."""
        return np.arccos(np.clip(self.R_meas[:, 2, 2], -1, 1))

    @property
    def azimuth_rad(self) -> np.ndarray:
        """Direction of the platform z axis projected on the base xy plane."""
        return np.arctan2(self.R_meas[:, 1, 2], self.R_meas[:, 0, 2])

    @property
    def tau_load_A_Nm(self) -> np.ndarray:
        """Moment the cables must carry: measured external moment plus the nominal weight moment.

        Returns
        -------
        numpy.ndarray
            Shape (n, 3) (N m, in {A}).
        """
        return self.rows.tau_meas_A_Nm + self.tau_weight_A_Nm

    def linearised_zeta(self, g: np.ndarray) -> np.ndarray:
        """Pose residual (rad) a balance residual ``g`` implies: ``G^-1 g``."""
        return np.linalg.solve(self.G, g[..., None])[..., 0]

    def take(self, idx: np.ndarray) -> "ResidualTable":
        """The rows ``idx`` of this table (the instrument model is shared).

        Parameters
        ----------
        idx : numpy.ndarray
            Row indices or a boolean mask.

        Returns
        -------
        ResidualTable
            A new table with those rows.
        """
        idx = np.asarray(idx)
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        out: dict[str, Any] = {
            k: (v.take(idx) if isinstance(v, Rows) else v if isinstance(v, InstrumentNoise) else v[idx])
            for k, v in fields.items()}
        return ResidualTable(**out)


def rms(zeta: np.ndarray) -> float:
    """``sqrt(mean ||zeta_i||^2)``."""
    return float(np.sqrt(np.mean(np.sum(np.asarray(zeta) ** 2, axis=-1)))) if len(zeta) else float("nan")


def pose_residuals(R_pred: np.ndarray, R_meas: np.ndarray) -> np.ndarray:
    """``log(R_pred^T R_meas)`` (n, 3), rad."""
    return so3.log(np.swapaxes(R_pred, -1, -2) @ R_meas)


def branches(cycle: np.ndarray, tau_meas: np.ndarray) -> np.ndarray:
    """Loading (+1) up to the row farthest (in moment) from the cycle's first row, unloading (-1) after."""
    out = np.zeros(len(cycle), int)
    for c in np.unique(cycle):
        idx = np.flatnonzero(cycle == c)
        d = np.linalg.norm(tau_meas[idx] - tau_meas[idx[0]], axis=1)
        peak = int(np.argmax(d))
        out[idx[1:peak + 1]] = 1
        out[idx[peak + 1:]] = -1
    return out


#: A row whose pose noise under the instrument model exceeds this multiple of its log's median is ill-conditioned
#: (:func:`ill_conditioned_rows`). Over the 94 logs of the validation folders the largest ratio was 14 (one row of
#: ``oracle_hard/combo_holes_mass``, two of its cables slack in the rig file's model at the measured pose), the next
#: 3.1 (a soft rig's lightest loads carry 2-3 times the noise of its heaviest); a suggested row that pulled a link
#: compliance's cable slack in the model: 100.
ILL_ROW_FACTOR = 10.0
#: Ill-conditioned rows are left out only while they are at most this share of the log (more: the log is not
#: this rig's, or the rig file is far off, and :func:`csjm_opt.diagnose.data.extra.check_rows_belong` speaks).
ILL_ROW_SHARE = 0.1


def row_pose_noise_rad(table: ResidualTable) -> np.ndarray:
    """Each row's pose noise under the instrument model, ``sqrt(tr Cov_zeta_i)`` (rad, (n,))."""
    return np.sqrt(np.sum(np.linalg.inv(table.whiten) ** 2, axis=(1, 2)))


def ill_conditioned_rows(table: ResidualTable) -> np.ndarray:
    """Rows (indices) where the rig file's model is nearly singular at the measured pose.

    The instrument noise reaches the pose through the nominal tangent ``G^-1``; where a cable of the model is slack
    at the measured pose (the rig held it taut: the model is off there) the joint is nearly free in the model, and
    the row's predicted pose noise and its residual grow by orders of magnitude. Such a row carries almost no
    weight in the fits (whitened), but it swamps every summary in rad: on a log of 168 rows one such row (100
    times the median) raised the instrument floor from 3.8 to 30 mrad and hid a link compliance at 3x the floor.
    Rows whose noise exceeds ``ILL_ROW_FACTOR`` times the log's median, while at most ``ILL_ROW_SHARE`` of the log.
    """
    sd = row_pose_noise_rad(table)
    bad = sd > ILL_ROW_FACTOR * np.median(sd)
    return np.flatnonzero(bad) if bad.mean() <= ILL_ROW_SHARE else np.zeros(0, int)


#: A row the model that fits the log does not come near and that stands apart from its cycle neighbours, each by more
#: than this multiple of the log's median (whitened norms), is a gross outlier (:func:`gross_rows`): a tracker glitch
#: or a force spike. Over the 94 logs of the validation folders the largest such ratio (the smaller of the two) is 3.5
#: (a Coulomb friction log's first row), over the 242 step-study logs 3.7; a moment spike of 0.5 N m (25 times the
#: sensor noise) kept in one row of 132 raised that log's noise floor from 3.5 to 5.6 mrad.
GROSS_ROW_FACTOR = 6.0
#: Gross outliers are left out only while they are at most this share of the log (more: heavy-tailed noise or an
#: effect the models miss, which the diagnosis reports rather than drops).
GROSS_ROW_SHARE = 0.05


def whitened_norm2(table: ResidualTable, zeta: np.ndarray) -> np.ndarray:
    """Each row's ``|W_i zeta_i|^2`` under the instrument model of ``table`` (``zeta`` (n, 3) in rad)."""
    return np.sum((table.whiten @ np.asarray(zeta)[..., None])[..., 0] ** 2, axis=1)


def cycle_deviation(zeta: np.ndarray, cycle: np.ndarray) -> np.ndarray:
    """Each row's residual less the mean of its neighbours in the same cycle.

    The neighbours are the rows before and after it in log order (one at a cycle's ends; zero in a cycle of one
    row). A smooth effect leaves little; a glitch stands out.
    """
    zeta = np.asarray(zeta, float)
    out = np.zeros_like(zeta)
    for c in np.unique(cycle):
        idx = np.flatnonzero(cycle == c)
        if len(idx) < 2:
            continue
        z = zeta[idx]
        nb = np.empty_like(z)
        nb[1:-1] = 0.5 * (z[:-2] + z[2:])
        nb[0], nb[-1] = z[1], z[-2]
        out[idx] = z - nb
    return out


def left_out_residuals(table: ResidualTable, zeta: np.ndarray, jac: np.ndarray | None, free: np.ndarray | None,
                       n_obs: int) -> np.ndarray:
    """Training residuals ``zeta`` (rad, (n, 3)) as if each row had been left out of the fit that made them.

    A fit bends toward each of its rows by the row's leverage ``H_ii = J_i (J^T J)^-1 J_i^T`` (3 x 3, ``J`` the fit's
    whitened Jacobian ``jac`` over its ``free`` parameters, data rows first, ``n_obs = 3 n`` of them, then its
    priors); the left-out residual is ``(I - H_ii)^-1`` times the row's whitened residual (exact for a linear least
    squares fit), taken back to rad through ``table``'s whitening. A model with many parameters (36 hole offsets)
    hides a spike in its training rows that its left-out residual shows. Returned unchanged without a Jacobian.
    """
    if jac is None or free is None or n_obs != 3 * len(table):
        return zeta
    J = jac[:, free]
    A = np.linalg.pinv(J.T @ J)
    Jd = J[:n_obs].reshape(len(table), 3, -1)
    H = Jd @ A @ Jd.transpose(0, 2, 1)
    w = (table.whiten @ np.asarray(zeta)[..., None])[..., 0]
    w_out = np.linalg.solve(np.eye(3) - H + 1e-12 * np.eye(3), w[..., None])[..., 0]
    return np.linalg.solve(table.whiten, w_out[..., None])[..., 0]


def gross_rows(table: ResidualTable, model_zeta: np.ndarray,
               nominal_zeta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows (indices) that are gross outliers, and every row's outlier ratio.

    A row's ratio is the smaller of two whitened norms, each over its median across the log: its residual under the
    model that fits the log (``model_zeta``, (n, 3)), and its nominal residual's departure from its cycle
    neighbours (:func:`cycle_deviation` of ``nominal_zeta``). An
    effect, however large, is either followed by the model or smooth within a cycle; a tracker glitch or a force
    spike in one row is neither. Rows above ``GROSS_ROW_FACTOR`` are gross while at most ``GROSS_ROW_SHARE`` of the
    log.
    """
    q_model = whitened_norm2(table, model_zeta)
    q_local = whitened_norm2(table, cycle_deviation(nominal_zeta, table.cycle))
    ratio = np.sqrt(np.minimum(q_model / max(float(np.median(q_model)), 1e-300),
                               q_local / max(float(np.median(q_local)), 1e-300)))
    bad = ratio > GROSS_ROW_FACTOR
    return (np.flatnonzero(bad) if bad.mean() <= GROSS_ROW_SHARE else np.zeros(0, int)), ratio


def compute_residuals(rig: Rig, log: MeasurementLog, noise: InstrumentNoise | None = None) -> ResidualTable:
    """Nominal residuals of every row of ``log`` (forward statics warm-started at the measured pose)."""
    noise = noise or InstrumentNoise.paper()
    R_meas = log.R
    model = AugmentedModel(rig)
    theta = model.x0()
    rows0 = Rows(log.rest_lengths_m, log.tau_ext_A_Nm, np.asarray(log.cycle), np.zeros(np.shape(log.rest_lengths_m)))
    sol = model.predict_poses(rows0, theta, R_meas)
    lengths, _ = kin.cable_terms(R_meas, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    rows = Rows(log.rest_lengths_m, log.tau_ext_A_Nm, np.asarray(log.cycle), cable_steps(log.cycle, lengths),
                log_steps_m=log_steps(lengths), rest_steps_m=log_steps(np.asarray(log.rest_lengths_m, float)))
    g = model.balance(R_meas, rows, theta)
    G = kin.tangent(lambda R: model.balance(R, rows, theta), R_meas, g)
    whiten = np.linalg.inv(np.linalg.cholesky(pose_noise_cov(G, noise)))
    mr = rig.platform_mass_kg * np.asarray(rig.com_A_m)
    tau_w = kin.weight_moment(R_meas, mr, np.asarray(rig.gravity_B_m_per_s2))
    return ResidualTable(np.asarray(log.cycle), rows, R_meas, sol.R, sol.converged(1e-6),
                         pose_residuals(sol.R, R_meas), g, G, whiten,
                         branches(log.cycle, log.tau_ext_A_Nm), tau_w, noise)


def pose_noise_cov(G: np.ndarray, noise: InstrumentNoise) -> np.ndarray:
    """Covariance (n, 3, 3) of a predicted-minus-measured pose under instrument noise.

    For tangent ``G``: moment noise through ``G^-1`` plus tracker noise (rad^2).
    """
    Ginv = np.linalg.inv(G)
    cov = (Ginv * np.asarray(noise.tau_sigma_Nm) ** 2) @ np.swapaxes(Ginv, 1, 2)
    return cov + (noise.angle_sigma_rad ** 2 + 1e-12) * np.eye(3)
