"""Sweep runner: evaluate many designs, in parallel, resumably.

:func:`run_sweep` evaluates every design of a :class:`SweepSpec` that the
result file (:class:`ResultStore`) does not already hold, appends each
finished design as it arrives, and shows a progress bar. Designs run on

* local processes (``concurrent.futures.ProcessPoolExecutor``, ``workers``
  of them, 2 by default; ``workers=1`` runs in this process), or
* a Dask cluster: ``scheduler="tcp://host:8786"`` connects to a running
  ``distributed`` scheduler, ``dask=True`` without an address starts a
  ``LocalCluster``. The same function evaluates each design on every
  backend and a design's result depends only on its parameters and the
  settings, so all backends give identical records (apart from timings).

A design is identified by a hash of the evaluation settings and its
parameters, so a resumed run (or a larger grid over the same settings)
skips every design already in the file.

Local worker processes are started by a fork server (``spawn`` where there is
none), never forked from the sweep itself: they inherit neither the locked
result file nor the OpenMP state of compiled kernels (forking a process that
has used GNU OpenMP aborts the child). They die with the sweep, whatever signal
ends it (SIGKILL included): each asks the kernel for SIGKILL when its parent
dies (``prctl(PR_SET_PDEATHSIG)`` on Linux; the fork server exits when the
sweep does) and a thread also watches the sweep's pid. A killed sweep leaves
no process behind and no lock held: running the same command again resumes it.
"""

from __future__ import annotations

import concurrent.futures
import concurrent.futures.process
import ctypes
import dataclasses
import hashlib
import json
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from ..errors import CsjmError, DesignError, SolverError
from .geometry import design_rig
from .metrics import evaluate
from .store import ResultStore
from .sweep_file import EvaluationSettings, SweepSpec

#: Record keys that depend on the machine, not on the design (left out of comparisons).
TIMING_KEYS = ("seconds",)


@dataclasses.dataclass(frozen=True, eq=False)
class SweepResult:
    """Records of every design of the sweep, in sweep order, and run statistics."""

    records: list[dict[str, Any]]
    computed: int            # designs evaluated in this run
    skipped: int             # designs found in the result file
    seconds: float           # wall time of this run
    complete: bool           # False when stopped early (stop_after)
    duplicates: int = 0      # repeated lines in the result file (ignored)

    @property
    def designs_per_second(self) -> float:
        """Designs evaluated per wall-clock second in this run (0 when none were)."""
        return self.computed / self.seconds if self.computed and self.seconds > 0 else 0.0

    def as_json(self) -> dict[str, Any]:
        """The ``csjm sweep --json`` document.

        Returns
        -------
        dict
            ``{"designs": [...], "designs_per_second", "computed", "skipped", "seconds",
            "complete"}`` (keys in docs/conventions.md).
        """
        designs = []
        for r in self.records:
            designs.append({"params": r["params"], "status": r["status"],
                            "workspace_fraction": r["workspace_fraction"],
                            "min_stiffness_Nm_per_rad": r["min_stiffness_Nm_per_rad"],
                            "metrics": r["metrics"], "error": r["error"], "id": r["id"]})
        return {"designs": designs, "designs_per_second": self.designs_per_second,
                "computed": self.computed, "skipped": self.skipped, "seconds": self.seconds,
                "complete": self.complete}


def design_id(settings_digest: str, params: dict[str, float]) -> str:
    """Stable identifier of a design under given settings."""
    text = json.dumps({"settings": settings_digest, "params": params}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def evaluate_design(params: dict[str, float], settings: EvaluationSettings) -> dict[str, Any]:
    """Metrics record of one design, as stored in a sweep's result file.

    Parameters
    ----------
    params : dict of str to float
        Design parameters (names in :data:`csjm_opt.design.PARAMETERS`).
    settings : EvaluationSettings
        Base design, sampling, loads and metric options of the sweep.

    Returns
    -------
    dict
        ``{"params", "status", "workspace_fraction", "min_stiffness_Nm_per_rad", "metrics",
        "error"}``; ``status`` is ``"ok"``, ``"invalid"`` (geometry rejected, ``error`` says why)
        or ``"error"``. Never raises for a bad design: the record carries the reason.
    """
    start = time.perf_counter()
    try:
        rig = design_rig({**settings.base, **params}, settings.limits)
    except CsjmError as exc:
        return {"params": params, "status": "invalid", "error": str(exc), "metrics": None,
                "workspace_fraction": None, "min_stiffness_Nm_per_rad": None,
                "seconds": time.perf_counter() - start}
    try:
        m = evaluate(rig, settings.sampling, settings.loads, settings.options).as_dict()
    except CsjmError as exc:  # deterministic: recorded, so a resumed run does not retry it
        return {"params": params, "status": "error", "error": f"{type(exc).__name__}: {exc}",
                "metrics": None, "workspace_fraction": None, "min_stiffness_Nm_per_rad": None,
                "seconds": time.perf_counter() - start}
    return {"params": params, "status": "ok", "error": None, "metrics": m,
            "workspace_fraction": m["workspace_fraction"],
            "min_stiffness_Nm_per_rad": m["min_stiffness_Nm_per_rad"],
            "seconds": time.perf_counter() - start}


def run_sweep(spec: SweepSpec, out: str | Path, workers: int = 2, scheduler: str | None = None,
              dask: bool = False, progress: bool | None = None,
              stop_after: int | None = None, connect_timeout_s: float = 10.0) -> SweepResult:
    """Evaluate the designs of ``spec`` missing from ``out`` and return all of them.

    Each finished design is appended to ``out`` (JSON Lines, flushed and fsynced); running again
    resumes, skipping finished designs.

    Parameters
    ----------
    spec : SweepSpec
        The sweep (from :meth:`SweepSpec.from_toml`).
    out : str or Path
        Result file; created, or resumed when it exists with the same settings.
    workers : int, optional
        Local worker processes (1 runs in this process); with ``dask``, the local cluster size.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``).
    dask : bool, optional
        Run on Dask; without ``scheduler``, on a local cluster.
    progress : bool, optional
        Show a progress bar on stderr; ``None`` shows it only on a terminal.
    stop_after : int, optional
        Stop after this many designs were written (an orderly interruption).
    connect_timeout_s : float, optional
        Longest wait for a Dask scheduler (s).

    Returns
    -------
    SweepResult
        Every design's record (finished before and now), counts and speed; ``as_json()`` gives
        the ``csjm sweep --json`` document.

    Raises
    ------
    DesignError
        If ``workers < 1``, or ``out`` was made with other settings or is locked by a running sweep.
    SolverError
        If a worker process dies.
    """
    if workers < 1:
        raise DesignError(f"workers must be >= 1, got {workers}", "workers")
    settings = spec.settings
    digest = settings.digest()
    designs = spec.designs()
    ids = [design_id(digest, p) for p in designs]
    start = time.perf_counter()
    computed = 0
    with ResultStore(out, digest) as store:
        todo = [(i, p) for i, (p, d) in enumerate(zip(designs, ids)) if d not in store.records]
        todo = list({ids[i]: (i, p) for i, p in todo}.values())   # a grid may repeat a design
        skipped = len(designs) - len(todo)
        bar = _progress(len(designs), skipped, progress)
        try:
            if dask or scheduler:
                stream = _run_dask(todo, settings, scheduler, workers, connect_timeout_s)
            elif workers == 1 or len(todo) <= 1:
                stream = ((i, evaluate_design(p, settings)) for i, p in todo)
            else:
                stream = _run_processes(todo, settings, workers)
            for i, record in stream:
                record.update(id=ids[i], index=i, settings=digest)
                store.append(record)
                computed += 1
                bar.update(1)
                if stop_after is not None and computed >= stop_after:
                    getattr(stream, "close", lambda: None)()
                    break
        finally:
            bar.close()
        records = [{**store.records[d], "params": p} for d, p in zip(ids, designs) if d in store.records]
    return SweepResult(records=records, computed=computed, skipped=skipped,
                       seconds=time.perf_counter() - start, complete=len(records) == len(designs),
                       duplicates=store.duplicates)


def _pool_context() -> Any:
    """A fork server (modules preloaded, so workers start fast), or ``spawn`` where there is none."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["csjm_opt.design.sweep"])
        return ctx
    return multiprocessing.get_context("spawn")  # pragma: no cover - Windows


def _run_processes(todo: list[tuple[int, dict]], settings: EvaluationSettings,
                   workers: int) -> Iterator[tuple[int, dict[str, Any]]]:
    pool = concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=_pool_context(),
                                                  initializer=_worker_init, initargs=(os.getpid(),))
    try:
        futures = {pool.submit(evaluate_design, p, settings): i for i, p in todo}
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


def _run_dask(todo: list[tuple[int, dict]], settings: EvaluationSettings, scheduler: str | None,
              workers: int, timeout_s: float) -> Iterator[tuple[int, dict[str, Any]]]:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError as exc:  # pragma: no cover - dask[distributed] is a dependency
        raise DesignError("the Dask option needs dask[distributed] installed", "--scheduler") from exc
    cluster = None
    try:
        if scheduler:
            client = Client(scheduler, timeout=f"{timeout_s}s")
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
    except (OSError, TimeoutError, ValueError) as exc:
        if cluster is not None:
            cluster.close()
        raise DesignError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}", "--scheduler") from exc
    try:
        yield from dask_stream(client, todo, settings, as_completed)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def dask_stream(client: Any, todo: list[tuple[int, dict]], settings: EvaluationSettings,
                as_completed: Callable) -> Iterator[tuple[int, dict[str, Any]]]:
    """Evaluate ``todo`` on a Dask ``client``; yields (index, record) as designs finish."""
    futures = {}
    try:
        shared = client.scatter(settings, broadcast=True)
        for i, p in todo:
            futures[client.submit(evaluate_design, p, shared, pure=False)] = i
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        client.cancel(list(futures))


def _progress(total: int, done: int, show: bool | None) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc="designs", unit="design", file=sys.stderr,
                disable=None if show is None else not show, smoothing=0.1)
