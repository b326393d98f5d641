"""The resumable runner the diagnosis studies share: one JSON line per finished case.

A study lists its cases (dicts with a unique ``id``), runs the ones its ``OUT.jsonl`` does
not hold yet, appends each record as it finishes (a rerun resumes), and summarises every
record it has. Failed cases are recorded with an ``error`` key and reported, not summarised.
Studies are scripts, not part of the package: run them from the repository root as modules
(``python -m studies.<study>.<script>``), so that ``studies._runner`` imports.
"""

from __future__ import annotations

import concurrent.futures
import json
import sys
from pathlib import Path
from typing import Callable, Iterable, Iterator

from csjm_opt._fileio import atomic_write_text


def read_records(path: Path) -> dict[str, dict]:
    """Records already in ``path`` (a JSON line each), by ``id``; empty when there is no file."""
    done: dict[str, dict] = {}
    if path.exists():
        for line in path.read_text().splitlines():
            if line.strip():
                rec = json.loads(line)
                done[rec["id"]] = rec
    return done


def pool_stream(run_one: Callable[[dict], dict], todo: list[dict], workers: int) -> Iterator[dict]:
    """Records of ``todo`` as a process pool of ``workers`` finishes them (one worker: in this process).

    An exception in a case ends the stream at once: the cases still queued are cancelled (a pool
    left to finish them would run for hours with nothing recorded and no progress shown).
    """
    if workers <= 1:
        for j in todo:
            yield run_one(j)
        return
    pool = concurrent.futures.ProcessPoolExecutor(workers)
    try:
        for f in concurrent.futures.as_completed([pool.submit(run_one, j) for j in todo]):
            yield f.result()
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def run_and_append(records: Iterable[dict], total: int, path: Path, done: dict[str, dict], desc: str,
                   no_progress: bool = False) -> None:
    """Append each record to ``path`` as it arrives (flushed: a killed run keeps what finished)."""
    from tqdm import tqdm

    bar = tqdm(total=total, file=sys.stderr, desc=desc, disable=no_progress or None)
    with path.open("a") as fh:
        for rec in records:
            fh.write(json.dumps(rec) + "\n")
            fh.flush()
            done[rec["id"]] = rec
            bar.update(1)
    bar.close()


def finished(done: dict[str, dict], path: Path, what: str = "cases") -> list[dict]:
    """The records without an error (the failed ones are reported on stderr)."""
    failed = [r for r in done.values() if "error" in r]
    if failed:
        print(f"{len(failed)} {what} failed (recorded in {path}): " + "; ".join(r["error"] for r in failed[:3]),
              file=sys.stderr)
    return [r for r in done.values() if "error" not in r]


def run_and_summarise(run_one: Callable[[dict], dict], jobs: list[dict], out: str, desc: str, workers: int,
                      no_progress: bool, summarise: Callable[[list[dict]], str]) -> None:
    """Run the ``jobs`` ``OUT.jsonl`` does not hold yet (``out`` without its suffix), then write ``OUT.md``
    (atomically) from the records of ``jobs``, in their order, and print it."""
    path = Path(out + ".jsonl")
    done = read_records(path)
    todo = [j for j in jobs if j["id"] not in done]
    run_and_append(pool_stream(run_one, todo, workers), len(todo), path, done, desc, no_progress)
    text = summarise([done[j["id"]] for j in jobs if j["id"] in done])
    atomic_write_text(out + ".md", text)
    print(text)
