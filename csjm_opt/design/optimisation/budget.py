"""A hard bound on the NLP evaluations of one IPOPT solve.

IPOPT evaluates the NLP once at its starting point and then, per iteration,
at the trial points of its line search. With a budget the solver is built with
options that bound the trial points of an iteration: a trial step is accepted
after :data:`ACCEPT_AFTER_STEPS` backtracking steps
(``accept_after_max_steps``), without second-order corrections
(``max_soc = 0``) and without the watchdog (whose failed trials would be
evaluated again), so an iteration evaluates the NLP at most
:data:`EVALUATIONS_PER_ITERATION` times. :class:`IterationStop`, IPOPT's
iteration callback, ends the solve (``User_Requested_Stop``) once the
iterations allowed by the evaluations left are done: a solve given ``n``
evaluations makes at most ``1 + k EVALUATIONS_PER_ITERATION <= n``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

#: Backtracking steps after which IPOPT accepts a trial point (bounded solves only).
ACCEPT_AFTER_STEPS = 4
#: Most NLP evaluations of one IPOPT iteration of a bounded solve (the first trial and the backtracking ones).
EVALUATIONS_PER_ITERATION = ACCEPT_AFTER_STEPS + 1
#: IPOPT options of a bounded solver.
BOUNDED_OPTIONS: dict[str, Any] = {"accept_after_max_steps": ACCEPT_AFTER_STEPS, "max_soc": 0,
                                   "watchdog_shortened_iter_trigger": 0}
#: IPOPT's status when the callback ended the solve.
STOPPED = "User_Requested_Stop"


class IterationStop(ca.Callback):  # type: ignore[misc]
    """IPOPT's iteration callback: ends the solve after ``allowed`` iterations (``None``: never).

    Parameters
    ----------
    nx, ng, npar : int
        Sizes of the NLP's variables, constraints and parameters.
    """

    def __init__(self, nx: int, ng: int, npar: int):
        ca.Callback.__init__(self)
        self.sizes = {"x": nx, "f": 1, "g": ng, "lam_x": nx, "lam_g": ng, "lam_p": npar}
        self.allowed: int | None = None
        self.calls = 0
        self.construct("csjm_iteration_stop", {})

    def get_n_in(self) -> int:  # noqa: D102 - CasADi's callback interface
        return int(ca.nlpsol_n_out())

    def get_n_out(self) -> int:  # noqa: D102
        return 1

    def get_name_in(self, i: int) -> str:  # noqa: D102
        return str(ca.nlpsol_out(i))

    def get_name_out(self, i: int) -> str:  # noqa: D102
        return "ret"

    def get_sparsity_in(self, i: int) -> Any:  # noqa: D102
        return ca.Sparsity.dense(self.sizes.get(str(ca.nlpsol_out(i)), 0), 1)

    def eval(self, arg: Any) -> list[int]:  # noqa: D102
        self.calls += 1                       # the first call reports iteration 0 (the start)
        return [int(self.allowed is not None and self.calls - 1 >= self.allowed)]

    def arm(self, evaluations: int | None) -> None:
        """Allow the next solve ``evaluations`` NLP evaluations (``None``: no bound).

        Parameters
        ----------
        evaluations : int or None
        """
        self.calls = 0
        self.allowed = None if evaluations is None else max((evaluations - 1) // EVALUATIONS_PER_ITERATION, 0)


def evaluations_of(stats: dict[str, Any]) -> int:
    """NLP evaluations of a finished solve (IPOPT's count of constraint evaluations, line search included).

    Parameters
    ----------
    stats : dict
        ``solver.stats()``.

    Returns
    -------
    int
    """
    return int(max(stats.get("n_call_nlp_g", 0), stats.get("n_call_nlp_f", 0), 1 if stats.get("iter_count") else 0))
