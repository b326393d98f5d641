"""The paper's printed numbers (Tables 1-4), exactly as printed, and the errata-corrected R0.

Nothing here is computed: these are the figures of the paper, to be checked
(:mod:`csjm_opt.identification.paper_tables`), never trusted. The errata are listed in docs/conventions.md.
Arrays are read-only.
"""

from __future__ import annotations

import numpy as np


def _ro(value) -> np.ndarray:
    arr = np.array(value, dtype=float)
    arr.setflags(write=False)
    return arr


#: Table 1, laser tracker: measurement uncertainty ``15 um + 6 um/m`` (of distance).
TABLE1_TRACKER_U0_M = 15e-6
TABLE1_TRACKER_U_PER_M = 6e-6
#: Table 2, F/T sensor: ranges (N, N m) and 95 % uncertainties (fraction of full scale),
#: order fx, fy, fz, tau_x, tau_y, tau_z.
TABLE2_FT_RANGE = _ro([145.0, 145.0, 290.0, 5.0, 5.0, 5.0])
TABLE2_FT_U95_FRACTION = _ro([0.0125, 0.0100, 0.0075, 0.0125, 0.0150, 0.0125])

#: Section IV-A: platform weight G (N) and its point of application in {A} (m).
GRAVITY_N = 4.82
R_G_A_M = _ro([0.0, 0.0, 0.081])

#: Table 3, original pose R0 as printed: element (3, 2) is +0.300 (erratum 3), not a rotation.
R0_PRINTED = _ro([[0.992, -0.060, -0.111],
                  [0.090, 0.952, 0.292],
                  [0.088, 0.300, 0.950]])
#: R0 with the sign of element (3, 2) corrected to -0.300 (orthogonal to 1e-3).
R0_CORRECTED = _ro([[0.992, -0.060, -0.111],
                    [0.090, 0.952, 0.292],
                    [0.088, -0.300, 0.950]])
#: Table 3, pre-load ``A tau_0`` (N m): read as the total load at R0 (it is what K_L was built from).
TAU0_A_NM = _ro([-0.06, -3.08, 1.07])
TABLE3_K_D = _ro([[29.39, 0.75, 1.67],
                  [-2.53, 29.96, -1.07],
                  [-4.49, -1.42, 6.99]])
#: Printed K_L = -hat(tau0) (structure constants +-2, erratum 1); the corrected one is -1/2 hat(tau0).
TABLE3_K_L = _ro([[0.0, 1.07, 3.08],
                  [-1.067, 0.0, -0.06],
                  [-3.08, 0.06, 0.0]])
TABLE3_K = _ro([[29.39, 1.82, 4.75],
                [-3.60, 29.96, -1.14],
                [-7.57, -1.35, 6.99]])

#: Table 4, column A: load increments ``Delta A tau`` (N m), cases 1-5.
TABLE4_DTAU_A_NM = _ro([[2.71, -0.93, 0.74],
                        [1.94, -0.80, 0.65],
                        [2.85, -1.16, 0.68],
                        [1.80, -1.45, 0.58],
                        [2.34, -1.40, 0.54]])
#: Table 4, column B: actual (measured) poses.
TABLE4_R_ACT = _ro([
    [[0.961, -0.255, -0.104], [0.273, 0.930, 0.246], [0.034, -0.265, 0.964]],
    [[0.984, -0.151, -0.091], [0.169, 0.954, 0.246], [0.050, -0.257, 0.965]],
    [[0.968, -0.220, -0.122], [0.243, 0.940, 0.239], [0.062, -0.261, 0.963]],
    [[0.977, -0.152, -0.152], [0.189, 0.945, 0.266], [0.103, -0.288, 0.952]],
    [[0.971, -0.216, -0.104], [0.234, 0.948, 0.214], [0.052, -0.232, 0.971]],
])
#: Table 4, column C: estimated poses.
TABLE4_R_EST = _ro([
    [[0.968, -0.223, -0.117], [0.244, 0.947, 0.209], [0.064, -0.231, 0.971]],
    [[0.974, -0.192, -0.120], [0.216, 0.948, 0.233], [0.069, -0.253, 0.965]],
    [[0.968, -0.217, -0.124], [0.238, 0.950, 0.202], [0.073, -0.225, 0.971]],
    [[0.974, -0.176, -0.143], [0.206, 0.951, 0.233], [0.095, -0.256, 0.962]],
    [[0.973, -0.185, -0.137], [0.211, 0.953, 0.216], [0.091, -0.239, 0.967]],
])
#: Table 4, column D: estimation errors E_theta (rad) as printed.
TABLE4_E_THETA_RAD = _ro([0.016, 0.034, 0.023, 0.058, 0.046])
#: Figure 5 / Section IV-B: number of measurements used for Table 3.
N_MEASUREMENTS = 85
