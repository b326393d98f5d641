"""``link_compliance``: a compliance in series between the cable-driven platform and the measured body.

The tracked, loaded body is joined to the cable platform by a link with
symmetric compliance ``C`` (rad/(N m), in {A}); the moment it carries, the
external moment plus the body's weight, ``tau_m``, twists it by
``phi = C tau_m``: ``R_meas = R_cable exp(hat(phi))``. The cables balance
``exp(hat(phi)) tau_m``. Six parameters (upper triangle of ``C``; diagonal
``>= 0``). ``C`` and the nominal stiffness scale trade off (both soften the
joint), so the fit also starts from a soft link.
"""

from __future__ import annotations

import numpy as np

from ... import so3
from .base import Effect, one_hot

_IU = np.triu_indices(3)


def _right_jacobian(phi: np.ndarray) -> np.ndarray:
    """Right Jacobian of SO(3) (n, 3, 3): ``exp(phi + d) = exp(phi) exp(J_r(phi) d)`` to first order."""
    th = np.linalg.norm(phi, axis=-1)[..., None, None]
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    a = np.where(small, 0.5 - th ** 2 / 24.0, (1.0 - np.cos(ths)) / ths ** 2)
    b = np.where(small, 1.0 / 6.0 - th ** 2 / 120.0, (ths - np.sin(ths)) / ths ** 3)
    K = so3.hat(phi)
    return np.eye(3) - a * K + b * (K @ K)


def compliance_matrix(p: np.ndarray) -> np.ndarray:
    """Symmetric compliance matrix from its upper triangle.

    Parameters
    ----------
    p : numpy.ndarray
        The six upper-triangle entries ``C_11, C_12, C_13, C_22, C_23, C_33`` (rad/(N m)).

    Returns
    -------
    numpy.ndarray
        The symmetric matrix ``C`` (rad/(N m), in {A}), shape (3, 3).
    """
    C = np.zeros((3, 3))
    C[_IU] = p
    return C + np.triu(C, 1).T


#: ``compliance_matrix`` of each unit parameter vector (6, 3, 3): C is linear in its parameters.
_UNIT_C = np.stack([compliance_matrix(e) for e in np.eye(6)])


class LinkCompliance(Effect):
    """Symmetric series compliance ``C`` (rad/(N m))."""

    name = "link_compliance"
    description = "series compliance C (rad/N m) between cable platform and measured body"
    #: the compliance turns the measured body by C times the whole load, and with it the tangent the residuals
    #: are taken through: from C = 0, a pair's fit reached up to 72 % of the evidence gap the step predicted
    #: (``studies/pair_screen``), effects with a tight step up to 25 %
    step_from_nominal = "loose"

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``C_{ij}_rad_per_Nm`` for the upper triangle ``i <= j``, six names (rad/(N m)).
        """
        return tuple(f"C_{i + 1}{j + 1}_rad_per_Nm" for i, j in zip(*_IU))

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            2e-3 rad/(N m) for each entry.
        """
        return np.full(6, 2e-3)

    @property
    def lower_bounds(self):
        """A compliance has a non-negative diagonal (necessary for positive semi-definite)."""
        return np.where(_IU[0] == _IU[1], 0.0, -np.inf)

    def default_ranges(self):
        """Up to 0.05 rad/(N m) per entry (a link 20x softer than the cables is not a rigid link)."""
        return {n: ((0.0 if i == j else -0.05), 0.05) for n, i, j in zip(self.param_names, *_IU)}

    def extra_starts(self):
        """A further start from a soft link (diagonal 5e-3 rad/(N m)).

        The stiffness scale and ``C`` trade off, both softening the joint.

        Returns
        -------
        list of numpy.ndarray
            One starting parameter vector.
        """
        # the stiffness scale and C trade off (both soften the joint): also start from a soft link
        return [np.where(_IU[0] == _IU[1], 5e-3, 0.0)]

    reads_load = True          # the twist follows the load: load parameters move the cables too

    def adjust_pose(self, ev, p):
        """Twist the cable platform back by ``phi = C (tau_ext + tau_weight)`` and record the link rotation.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            The upper triangle of ``C`` (rad/(N m)), shape (6,).
        """
        phi = (ev.tau_ext_A_Nm + ev.tau_weight_A_Nm) @ compliance_matrix(p)  # C symmetric
        E = so3.exp(phi)
        ev.R_cable = ev.R_cable @ np.swapaxes(E, 1, 2)
        ev.link_rotation = E @ ev.link_rotation

    def d_adjust_pose(self, ev, p, cols, d_load, d_eta, d_link):
        """Tangents of :meth:`adjust_pose`: ``E = exp(phi)`` moves by ``E hat(w)``, ``w = J_r(phi) dphi``.

        ``dphi = d(tau) C + tau dC``; the cable platform ``R E^T`` turns by ``E (eta - w)`` (right rotation),
        the link's rotation ``E L`` by ``E hat(w) L + E dL``.
        """
        P = d_load.shape[-1]
        C = compliance_matrix(p)
        tau = ev.tau_ext_A_Nm + ev.tau_weight_A_Nm
        phi = tau @ C
        # C is linear in p: its tangent is C of the unit vectors, on this effect's columns
        dC = np.tensordot(_UNIT_C, one_hot(cols, P), axes=(0, 0))                # (3, 3, P)
        d_phi = C @ d_load + np.tensordot(tau, dC, axes=(1, 0))                  # C symmetric
        w = _right_jacobian(phi) @ d_phi
        E = so3.exp(phi)
        eta = E @ (d_eta - w)
        link = E[:, None] @ so3.hat(np.moveaxis(w, -1, 1)) @ ev.link_rotation[:, None]     # (n, P, 3, 3)
        link = np.moveaxis(link, 1, -1)
        if d_link is not None:
            link = link + np.einsum("nij,njkp->nikp", E, d_link)
        return eta, link

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``compliance_eigenvalues_rad_per_Nm``: the eigenvalues of ``C`` (rad/(N m)).
        """
        w = np.linalg.eigvalsh(compliance_matrix(p))
        return {"compliance_eigenvalues_rad_per_Nm": w.tolist()}
