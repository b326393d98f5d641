"""Compiled (numba) kernels of the closed loop, gathered from the layers that own them.

Forward statics (Newton on SO(3), rest-length state, ``log_so3``) live in
:mod:`csjm_opt.model.statics_kernels`, the shaping QP's matrices in
:mod:`csjm_opt.shaping.shaping_kernels`, the dense active-set QP in
:mod:`csjm_opt.planning.kernels`; this module re-exports them for the
controllers and plants. ``tests/control/test_loop_kernels.py`` checks them.
"""

from __future__ import annotations

from ..model.statics_kernels import (
    exp_so3,
    geometry,
    hat,
    length_hessians,
    log_so3,
    newton,
    rest_state,
    stiffness_basis,
    terms,
)
from ..planning.kernels import pdas
from ..shaping.shaping_kernels import shaping_qp

__all__ = ["exp_so3", "geometry", "hat", "length_hessians", "log_so3", "newton", "pdas", "rest_state",
           "shaping_qp", "stiffness_basis", "terms"]
