"""Whether a load cycle can determine K: excitation of the displacements and the refusal rule's limits.

See :mod:`csjm_opt.identification.identify_pose` for the refusal rule these limits enter.
"""

from __future__ import annotations

import numpy as np

from ..errors import IllConditionedData
from ..measurement.instruments import InstrumentNoise

#: Default largest accepted condition number of the (centred) excitation. A
#: load cycle along one direction gives 100-500 with the paper's noise (its
#: weakest "direction" is noise), a designed multi-direction cycle 1.5-4.
MAX_CONDITION = 100.0
#: Smallest singular value of the excitation, in units of the orientation noise, to call it determined.
NOISE_FLOOR_FACTOR = 3.0
#: Stated precision: largest accepted confidence half-width of an entry of K relative to ||K||_2.
MAX_RELATIVE_HALF_WIDTH = 0.2


# ------------------------------------------------------------------ design
def excitation(dzeta: np.ndarray, noise: InstrumentNoise | None = None,
               max_condition: float = MAX_CONDITION) -> tuple[float, np.ndarray]:
    """Condition number and singular values of the centred displacements.

    Parameters
    ----------
    dzeta : ndarray, shape (n, 3)
        Body-frame displacements from the reference row (rad).
    noise : InstrumentNoise, optional
        With it, the smallest singular value must exceed :data:`NOISE_FLOOR_FACTOR` times the
        orientation noise (scaled by ``sqrt(2 n)``).
    max_condition : float, optional
        Largest accepted condition number.

    Returns
    -------
    condition : float
        Largest over smallest singular value.
    singular_values_rad : ndarray, shape (3,)
        Singular values of the centred displacements, largest first (rad).

    Raises
    ------
    IllConditionedData
        When the displacements do not span three directions: rank below 3, condition above
        ``max_condition``, or a smallest singular value under the noise floor.
    """
    Z = dzeta - dzeta.mean(axis=0)
    s = np.linalg.svd(Z, compute_uv=False) if len(Z) else np.zeros(0)
    s = np.concatenate([s, np.zeros(3 - len(s))])[:3]
    rank = int(np.sum(s > s[0] * 1e-10)) if s[0] > 0 else 0
    cond = float(s[0] / s[2]) if s[2] > 0 else float("inf")
    floor = 0.0 if noise is None else NOISE_FLOOR_FACTOR * noise.angle_sigma_rad * np.sqrt(2 * len(Z))
    if rank < 3 or cond > max_condition or s[2] <= floor:
        raise IllConditionedData(
            f"displacements do not span three directions: singular values "
            f"{np.array2string(s, precision=3)} rad, condition {cond:.3g} (limit {max_condition:g})"
            + (f", noise floor {floor:.2g} rad" if floor else ""), cond, rank)
    return cond, s


def _check_rows(n: int, p: int) -> None:
    if n < p + 1:
        raise IllConditionedData(f"{n} rows cannot determine {p} parameters per axis "
                                 f"(need at least {p + 1})", float("inf"), n)


def weakest_load_direction(tau_load_A_Nm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit direction in {A} along which the centred load moments vary least, and their singular values (N m).

    The sign is fixed so that the largest component is positive.

    Parameters
    ----------
    tau_load_A_Nm : ndarray, shape (n, 3)
        Total load moments in {A} (N m).

    Returns
    -------
    direction_A : ndarray, shape (3,)
        Unit vector in {A}.
    singular_values_Nm : ndarray, shape (3,)
        Singular values of the centred moments, largest first, zero-padded (N m).
    """
    T = tau_load_A_Nm - tau_load_A_Nm.mean(axis=0)
    _, s, Vt = np.linalg.svd(T, full_matrices=True)
    u = Vt[-1]
    u = u if u[np.argmax(np.abs(u))] >= 0 else -u
    return u, np.concatenate([s, np.zeros(3 - len(s))])[:3]


def _missing(u: np.ndarray) -> str:
    v = np.round(u, 2) + 0.0
    return (f"the load moments barely vary along [{v[0]:.2f}, {v[1]:.2f}, {v[2]:.2f}] in {{A}}; add loads "
            "with a moment component along that direction (or pass allow_ill_conditioned / "
            "--allow-ill-conditioned)")
