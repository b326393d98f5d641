"""Sweep runner: evaluate many designs, in parallel, resumably.

:func:`run_sweep` evaluates every design of a :class:`SweepSpec` that the
result file (:class:`ResultStore`) does not already hold, appends each
finished design as it arrives, and shows a progress bar. Designs run on

* local processes (``concurrent.futures.ProcessPoolExecutor``, ``workers``
  of them; ``workers=1`` runs in this process). By default (``workers=None``)
  the sweep times its first designs in this process and starts
  :data:`AUTO_WORKERS` worker processes only if the rest would take longer
  than twice :data:`POOL_STARTUP_S` there: starting the workers (fork server,
  imports, loading the compiled kernels) costs about a second, more than a
  few hundred designs take in one process; or
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

import dataclasses
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ..._workers import default_workers
from ...errors import DesignError
from .._dask_backend import _run_dask, dask_stream
from .._worker_processes import _run_processes
from ..design_evaluation import TIMING_KEYS, design_id, evaluate_design
from ..evaluation_settings import EvaluationSettings
from .spec import SweepSpec
from .store import ResultStore

__all__ = ["SweepResult", "TIMING_KEYS", "dask_stream", "design_id", "evaluate_design", "run_sweep"]


#: Worker processes of an automatic local run (``workers=None``).
#: Kept for callers that read it; the worker count of the automatic mode is :func:`default_workers`.
AUTO_WORKERS = 2
#: Time (s) taken as the cost of starting the worker processes, in the automatic choice.
POOL_STARTUP_S = 1.0
#: Designs timed in this process before the automatic choice.
_TIMED_DESIGNS = 8


def run_sweep(spec: SweepSpec, out: str | Path, workers: int | None = None, scheduler: str | None = None,
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
        ``None`` (default): :func:`~csjm_opt._workers.default_workers` processes when the sweep is long enough to
        repay starting them, else this process (2 for a Dask cluster).
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
    if workers is not None and workers < 1:
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
                stream = _run_dask(todo, settings, scheduler, workers or default_workers(), connect_timeout_s)
            elif workers is None:
                stream = _run_auto(todo, settings)
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


def _run_auto(todo: list[tuple[int, dict]], settings: EvaluationSettings) -> Iterator[tuple[int, dict[str, Any]]]:
    """The first designs here, timed; the rest here too unless worker processes repay their start-up."""
    seconds = []
    for i, p in todo[:_TIMED_DESIGNS]:
        t0 = time.perf_counter()
        yield i, evaluate_design(p, settings)
        seconds.append(time.perf_counter() - t0)
    rest = todo[_TIMED_DESIGNS:]
    if not rest:
        return
    # the first design also loads the compiled kernels: the median of the others is the estimate
    per_design_s = float(np.median(seconds[1:]))
    n = default_workers()
    if n < 2 or len(rest) * per_design_s * (1.0 - 1.0 / n) < POOL_STARTUP_S:
        yield from ((i, evaluate_design(p, settings)) for i, p in rest)
    else:
        yield from _run_processes(rest, settings, n)


def _progress(total: int, done: int, show: bool | None) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc="designs", unit="design", file=sys.stderr,
                disable=None if show is None else not show, smoothing=0.1)


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
