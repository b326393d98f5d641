"""Running a sweep's designs on a Dask cluster (a running scheduler or a local cluster)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from ..errors import DesignError
from .design_evaluation import evaluate_design
from .evaluation_settings import EvaluationSettings


def _run_dask(todo: list[tuple[int, dict]], settings: EvaluationSettings | Any, scheduler: str | None,
              workers: int, timeout_s: float, fn: Callable = evaluate_design) -> Iterator[tuple[int, Any]]:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError as exc:
        raise DesignError('the Dask option needs the dask extra: pip install -e ".[dask]" (or '
                          '"csjm_opt[dask]")', "--dask") from exc
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
        yield from dask_stream(client, todo, settings, as_completed, fn)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def dask_stream(client: Any, todo: list[tuple[int, dict]], settings: EvaluationSettings | Any,
                as_completed: Callable, fn: Callable = evaluate_design) -> Iterator[tuple[int, Any]]:
    """Evaluate ``todo`` on a Dask ``client``, yielding ``(index, result)`` as they finish.

    ``fn(params, settings)`` is run per design (default: a sweep design's record).
    """
    futures = {}
    try:
        shared = client.scatter(settings, broadcast=True)
        for i, p in todo:
            futures[client.submit(fn, p, shared, pure=False)] = i
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        client.cancel(list(futures))
