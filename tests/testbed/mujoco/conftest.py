"""One designed load cycle of the paper rig and the row arguments of ``respond_rows`` for it."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.testbed import design_cycles


@pytest.fixture(scope="module")
def cycle(rig):
    """One designed load cycle on the paper rig (5 rows: up and down)."""
    return design_cycles(rig, 1, np.random.default_rng(21), steps=2)[0]


def rows_args(c, repeat=1):
    """``respond_rows`` arguments for ``repeat`` copies of cycle ``c`` (rest lengths, loads, cycle ids, poses)."""
    m = len(c.alphas)
    n = m * repeat
    return (np.repeat(c.rest_lengths_m[None], n, 0), np.tile(c.tau_ext_A_Nm, (repeat, 1)),
            np.repeat(np.arange(repeat), m), np.repeat(c.R_ref[None], n, 0))
