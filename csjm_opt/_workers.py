"""The one default number of worker processes (``--workers`` of every command, the library's ``None``)."""

from __future__ import annotations

import multiprocessing as mp
import os

from .errors import InvalidInput


def default_workers() -> int:
    """Worker processes to use by default: ``CSJM_WORKERS`` when set, else the cores this process may use.

    In a process started by :mod:`multiprocessing` (a worker of a pool) it is 1: the pool spreads the
    work over the cores already.

    Returns
    -------
    int
        At least 1.

    Raises
    ------
    InvalidInput
        ``CSJM_WORKERS`` is not a positive integer.
    """
    env = os.environ.get("CSJM_WORKERS", "").strip()
    if env:
        if not env.isdigit() or int(env) < 1:
            raise InvalidInput(f"CSJM_WORKERS must be a positive integer (got {env!r})", "CSJM_WORKERS")
        return int(env)
    if mp.current_process().daemon or mp.parent_process() is not None:
        return 1
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:                      # not on Linux
        return max(os.cpu_count() or 1, 1)
