"""Local worker processes of a sweep: started by a fork server, they die with the sweep.

See :mod:`csjm_opt.design.sweep.runner`.
"""

from __future__ import annotations

import concurrent.futures
import concurrent.futures.process
import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any

from ..errors import SolverError
from .design_evaluation import evaluate_design
from .evaluation_settings import EvaluationSettings


def _pool_context() -> Any:
    """A fork server (modules preloaded, so workers start fast), or ``spawn`` where there is none."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["csjm_opt.design.sweep.runner"])
        return ctx
    return multiprocessing.get_context("spawn")  # pragma: no cover - Windows


def _run_processes(todo: list[tuple[int, dict]], settings: EvaluationSettings | Any,
                   workers: int, fn: Any = evaluate_design) -> Iterator[tuple[int, Any]]:
    pool = concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=_pool_context(),
                                                  initializer=_worker_init, initargs=(os.getpid(),))
    try:
        futures = {pool.submit(fn, p, settings): i for i, p in todo}
        for future in concurrent.futures.as_completed(futures):
            yield futures[future], future.result()
    except concurrent.futures.process.BrokenProcessPool as exc:
        raise SolverError("a worker process died (out of memory or killed); finished designs are "
                          "saved, run the same command again to resume", "processes") from exc
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


_PR_SET_PDEATHSIG = 1


def _worker_init(sweep_pid: int) -> None:
    """Set up a worker: leave Ctrl-C to the sweep, die with the sweep.

    The sweep stops the pool on Ctrl-C and keeps the file whole. If it dies
    any other way, the kernel kills the worker when its parent (the fork
    server, which exits with the sweep) dies (Linux ``PR_SET_PDEATHSIG``), and
    a thread watching the sweep's pid does the same elsewhere, and covers a
    parent that died before the ``prctl``.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no libc prctl
            pass
    if not _alive(sweep_pid):
        os._exit(1)
    threading.Thread(target=_watch_sweep, args=(sweep_pid,), name="csjm-sweep-watch", daemon=True).start()


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie counts as dead)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - exists, owned by someone else
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            return fh.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except OSError:
        return True  # no /proc: kill(0) said it exists


def _watch_sweep(sweep_pid: int, interval_s: float = 0.5) -> None:
    while _alive(sweep_pid):
        time.sleep(interval_s)
    os._exit(1)
