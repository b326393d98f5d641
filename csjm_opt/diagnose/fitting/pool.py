"""Independent model fits of one diagnosis on several cores, in a deterministic order.

The candidates and pairs of a diagnosis are independent fits of the same rows: they can run in
worker processes. Each worker computes exactly what the serial loop computes (BLAS single-threaded,
floating-point warnings off, as in :func:`csjm_opt.diagnose.diagnose`), and the results come back in
the order of the items, so a parallel diagnosis is identical to a serial one.

Workers are forked (the shared state, rows and noise estimates, is inherited, not pickled); where
``fork`` is not available the fits run serially, and by default also in a process that is itself a
worker of a pool (a study diagnosing several logs at once uses the cores already). The environment
variable ``CSJM_WORKERS`` sets the default (e.g. ``CSJM_WORKERS=1`` on a shared machine, or under a
test runner that runs several processes itself).
"""

from __future__ import annotations

import multiprocessing as mp
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, Callable, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from ..._workers import default_workers
from ...errors import InvalidInput

_SHARED: dict[str, Any] = {}


def resolve_workers(workers: int | None) -> int:
    """``workers`` checked, or :func:`default_workers` for None.

    Parameters
    ----------
    workers : int or None
        Requested number of worker processes (1: serial).

    Returns
    -------
    int
        At least 1.

    Raises
    ------
    InvalidInput
        ``workers`` below 1.
    """
    if workers is None:
        return default_workers()
    if int(workers) < 1:
        raise InvalidInput(f"workers must be at least 1 (got {workers})", "workers")
    return int(workers)


def map_ordered(fn: Callable, shared: tuple, items: Sequence, workers: int,
                tick: Callable[[int], object] | None = None,
                cost: Callable[[Any], float] | None = None) -> list:
    """``[fn(*shared, item) for item in items]``, on up to ``workers`` forked processes.

    On workers the calls start in the order of decreasing ``cost`` (the longest first, so that a long fit
    does not start last while the other workers idle); the results come back in the order of ``items``
    whatever the order of the calls.

    Parameters
    ----------
    fn : callable
        A module-level function (its results must pickle: they travel back from the workers).
    shared : tuple
        Leading arguments common to every call (inherited by the forked workers, not pickled).
    items : sequence
        One call per item (each item pickles).
    workers : int
        Worker processes; 1 (or fewer than two items, or no ``fork``) runs the calls here, in order.
    tick : callable, optional
        Called with 1 as each call finishes (a progress bar's ``update``).
    cost : callable, optional
        Expected cost of an item's call (any scale; default: the order of ``items``).

    Returns
    -------
    list
        The results in the order of ``items``.
    """
    tick = tick or _no_tick
    if workers <= 1 or len(items) < 2 or "fork" not in mp.get_all_start_methods():
        out = []
        for item in items:
            out.append(fn(*shared, item))
            tick(1)
        return out
    # forked workers inherit what this process has loaded: numba's runtime (0.46 s at a process's first compiled
    # call) is loaded here by the log reader's compiled pass; what a worker loads first, every worker pays
    with ProcessPoolExecutor(min(workers, len(items)), mp_context=mp.get_context("fork"),
                             initializer=_init, initargs=(fn, shared)) as ex:
        order = sorted(range(len(items)), key=lambda i: -cost(items[i])) if cost is not None else range(len(items))
        submitted = {i: ex.submit(_call, items[i]) for i in order}
        futures = [submitted[i] for i in range(len(items))]
        try:
            for f in as_completed(futures):
                f.result()                  # an error (or Ctrl-C) stops the rest at once
                tick(1)
        except BaseException:
            ex.shutdown(wait=False, cancel_futures=True)
            raise
        return [f.result() for f in futures]


def _no_tick(n: int = 1) -> None:
    return None


def _init(fn: Callable, shared: tuple) -> None:
    """Worker start: the function and its shared arguments, BLAS on one thread (as the serial fits)."""
    _SHARED["fn"], _SHARED["shared"] = fn, shared
    _SHARED["limits"] = threadpool_limits(1)


def _call(item: Any) -> Any:
    with np.errstate(all="ignore"):
        return _SHARED["fn"](*_SHARED["shared"], item)
