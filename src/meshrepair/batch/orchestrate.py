"""Repair a whole collection of meshes on Dask (``dask.distributed``): a ``LocalCluster`` of
single-threaded worker processes on this machine by default, any running Dask scheduler when a
client (or, on the command line, ``--scheduler tcp://host:8786``) is given.

This module is orchestration only. One mesh is one Dask task
(:func:`meshrepair.batch.jobs.run_job`):
the task gets file paths and a small options dict, reads its mesh, calls the public function
(:func:`meshrepair.denoise`, :func:`~meshrepair.fill_holes`, :func:`~meshrepair.inpaint`,
:func:`~meshrepair.complete`), writes its output atomically and returns a small record; no mesh
ever travels through the scheduler. The client appends each record to ``OUT/batch.jsonl`` as it
arrives and, at the end, writes the collection report ``OUT/index.html``.

Failure handling is Dask's: a bad mesh is a failed record (the task never raises); a worker
process that dies (killed, out of memory past ``--memory-limit``) is restarted by its nanny and
the scheduler re-runs its task elsewhere, up to ``distributed.scheduler.allowed-failures`` times
(``retries`` for the local cluster), after which the mesh is recorded as failed
(``error_type="KilledWorker"``). Numeric code on a worker is single-threaded (one mesh per
process, no oversubscription): the local cluster gives its worker processes the thread
variables of :data:`meshrepair.batch.jobs.THREAD_ENV` (``LocalCluster(env=...)``, applied before the
worker imports meshrepair and numba; OpenBLAS/OpenMP/MKL are also in Dask's default
``pre-spawn-environ``, set before numpy loads), and on an external cluster the
:class:`distributed.diagnostics.plugin.Environ` nanny plugin sets them (restarting workers that
lack them). Each job also runs under ``threadpool_limits(1)``.
"""

from __future__ import annotations

import datetime
import logging
import os
import secrets
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path

from meshrepair import __version__
from meshrepair.batch.collection import (
    THUMBNAILS,
    RecordWriter,
    collect_inputs,
    is_done,
    read_records,
    remove_stale_temporaries,
)
from meshrepair.batch.jobs import TASKS, THREAD_ENV, check_options, run_job
from meshrepair.errors import MeshRepairError

log = logging.getLogger(__name__)

__all__ = ["TASKS", "connect", "run"]


@contextmanager
def connect(scheduler: str | None = None, *, workers: int | None = None,
            memory_limit: str | None = None, retries: int = 2) -> Iterator:
    """A ``distributed.Client``: to ``scheduler`` if given, else to a new ``LocalCluster``.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``). Its workers must have meshrepair
        installed and see the input and output folders.
    workers : int, optional
        Local worker processes (default: the number of cores), one thread each.
    memory_limit : str, optional
        Per local worker (e.g. ``"4GB"``; default Dask's ``"auto"``, the machine's memory shared
        among the workers); a worker above 95 % of it is restarted and its mesh retried.
    retries : int
        Local cluster: how many times a mesh whose worker died is re-run before it is recorded
        as failed (``distributed.scheduler.allowed-failures``).
    """
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        if workers is not None or memory_limit is not None:
            log.warning("--workers and --memory-limit apply to a local cluster; the workers of "
                        "%s keep their own settings", scheduler)
        try:
            client = Client(scheduler, timeout="30s")
        except (OSError, TimeoutError) as exc:
            raise MeshRepairError(f"cannot connect to the Dask scheduler {scheduler!r}: {exc}; "
                                  "is it running ('dask scheduler') and reachable?") from None
        try:
            yield client
        finally:
            client.close()
        return
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise MeshRepairError(f"workers must be a positive integer, got {workers!r}")
    if not isinstance(retries, int) or retries < 0:
        raise MeshRepairError(f"retries must be a non-negative integer, got {retries!r}")
    n = workers or os.cpu_count() or 1
    # env: set in each worker process before it imports meshrepair (numba reads its thread
    # count then); the BLAS/OpenMP variables are also in Dask's default pre-spawn-environ (set
    # before numpy loads). Not pre-spawn-environ here: that also changes this process's
    # environment, and numba refuses a changed NUMBA_NUM_THREADS once its threads exist.
    with dask.config.set({"distributed.scheduler.allowed-failures": retries}):
        try:
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   memory_limit=memory_limit or "auto", host="127.0.0.1",
                                   dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR,
                                   env=dict(THREAD_ENV))
        except (ValueError, TypeError) as exc:
            raise MeshRepairError(f"cannot start a local Dask cluster ({n} workers, memory "
                                  f"limit {memory_limit!r}): {exc}") from None
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def _thread_env() -> dict:
    return {k: os.environ.get(k) for k in THREAD_ENV}


def _single_threaded(client) -> None:
    """Make sure every worker process runs with :data:`THREAD_ENV` set before its numeric
    imports: if one lacks it, register Dask's ``Environ`` nanny plugin (it restarts the workers
    so that the variables are in place when they start)."""
    from distributed.diagnostics.plugin import Environ

    if all(v == THREAD_ENV for v in client.run(_thread_env).values()):
        return
    log.info("setting %s on the workers (restarting them)", ", ".join(THREAD_ENV))
    n = len(client.scheduler_info().get("workers", {}))
    client.register_plugin(Environ(THREAD_ENV), name="meshrepair-single-threaded")
    client.wait_for_workers(max(n, 1), timeout=120)


def _job(task: str, input: str, output: str, options: dict, thumbnails: str | None,
         thumbnail_size: int) -> dict:
    """The Dask task: one mesh (see :func:`meshrepair.batch.jobs.run_job`), plus the worker."""
    from distributed import get_worker

    lib = logging.getLogger("meshrepair")
    if not lib.handlers and not logging.getLogger().handlers:
        # the job keeps the library's warnings in its record (and index.html); without this,
        # Python's last-resort handler would also print them over the client's progress bar
        lib.addHandler(logging.NullHandler())
    rec = run_job(task, input, output, options, thumbnails=thumbnails,
                  thumbnail_size=thumbnail_size)
    try:
        w = get_worker()
        rec["worker"], rec["key"] = w.address, str(w.get_current_task())
    except ValueError:  # pragma: no cover - always on a worker here
        rec["worker"] = rec["key"] = None
    return rec


def _lost(task: str, inp: Path, out: Path, exc: BaseException) -> dict:
    """The record of a mesh whose task did not return (its workers died every time)."""
    name = type(exc).__name__
    msg = str(exc)
    if name == "KilledWorker":
        msg = ("the worker process repairing it died on every attempt (killed, or out of "
               f"memory: raise --memory-limit; see the worker logs): {exc}")
    rec = {"task": task, "input": str(inp), "output": str(out), "status": "failed",
           "error": msg, "error_type": name, "metrics": {}, "thumbnails": {}}
    try:
        st = inp.stat()
        rec["input_size"], rec["input_mtime_ns"] = st.st_size, st.st_mtime_ns
    except OSError:
        pass
    return rec


def run(paths, out_dir: str | os.PathLike, *, task: str, client=None, scheduler: str | None = None,
        workers: int | None = None, memory_limit: str | None = None, resume: bool = False,
        force: bool = False,
        pattern: str | None = None, retries: int = 2, thumbnails: bool = True,
        thumbnail_size: int = 160, report: bool = True,
        callback: Callable[[dict], None] | None = None, **options) -> list[dict]:
    """Repair every mesh of a collection with one task; returns one record per mesh.

    Parameters
    ----------
    paths : folder, glob pattern, list file, mesh file or list of paths
        See :func:`meshrepair.batch.collection.collect_inputs`; ``OUT/rel`` mirrors the input
        layout.
    out_dir : folder
        Created if missing. Holds the outputs, ``batch.jsonl``, ``index.html`` and
        ``thumbnails/``. An input is never overwritten (refused before any work).
    task : {"denoise", "fill", "inpaint", "complete"}
    client : distributed.Client, optional
        Run on this client's cluster; default: connect to ``scheduler`` if given, else start a
        LocalCluster (``workers``, ``memory_limit``, ``retries``; see :func:`connect`), after
        the inputs and outputs were checked, and close it at the end.
    resume : bool
        Skip meshes whose output exists and whose latest record says ``done`` for the same task,
        options, meshrepair version and input file (:func:`meshrepair.batch.collection.is_done`).
    force : bool
        Overwrite existing outputs (without it, and without a matching record under
        ``resume``, an existing output refuses the batch before any work).
    pattern : str, optional
        File-name pattern for a folder (default: every mesh suffix).
    thumbnails, thumbnail_size, report
        Before/after PNG thumbnails (rendered by the workers) and ``OUT/index.html``.
    callback : callable, optional
        Called with ``{"event": "start", "dashboard", "total", "todo", "skipped", "workers"}``
        once and ``{"event": "mesh", "record", "done", "failed", "running", "total"}`` per mesh.
    **options
        The task's options (:func:`meshrepair.batch.jobs.task_option_names`): keyword arguments of
        the
        public function, plus file options (inpaint ``region``; complete ``template``,
        ``region``, ``hole``, ...), which may use ``{stem}``, ``{name}``, ``{parent}``.

    Returns
    -------
    list of dict
        In input order: ``rel``, ``input``, ``output``, ``status`` ("done"/"failed"), ``error``,
        ``error_type``, ``seconds``, ``peak_rss_mb``, ``vertices``, ``faces``, ``out_vertices``,
        ``metrics``, ``worker``, ``task``, ``options``, ``version``, ``finished``; a mesh
        skipped by ``resume`` returns its earlier record with ``resumed=True``.
    """
    if task not in TASKS:
        raise MeshRepairError(f"unknown task {task!r}: choose one of {', '.join(TASKS)}")
    options = check_options(task, options)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise MeshRepairError(f"the output folder {str(out)!r} exists and is not a folder: "
                              "choose a folder name (it is made if missing)")
    if not isinstance(paths, (list, tuple)) and Path(paths).is_dir() and (
            Path(paths).resolve() == out.resolve()):
        raise MeshRepairError(f"the output folder {str(out)!r} is the input folder: choose "
                              "another one (outputs mirror the input layout there)")
    inputs = collect_inputs(paths, pattern=pattern, exclude=out)
    in_set = {p.resolve() for p, _ in inputs}
    previous = read_records(out) if resume else {}
    results: dict[str, dict] = {}
    todo, existing = [], []
    for p, rel in inputs:
        o = out / rel
        if o.resolve() in in_set:
            raise MeshRepairError(f"the output of {str(p)!r} would be the input {str(o)!r}: "
                                  "choose an output folder that is not the input folder")
        if resume and is_done(previous.get(rel), task=task, options=options,
                              version=__version__, input=p, output=o):
            results[rel] = {**previous[rel], "resumed": True}
            continue
        if o.exists() and not force:
            existing.append(o)
        todo.append((p, rel, o))
    if existing and resume:
        raise MeshRepairError(
            f"{len(existing)} outputs exist without a record of the same task, options, version "
            f"and input (e.g. {str(existing[0])!r}: other options, a changed input, or written "
            "by an interrupted run just before its record); add --force (force=True) to redo "
            "them, the meshes recorded as done are still skipped")
    if existing:
        raise MeshRepairError(
            f"{len(existing)} outputs exist already (e.g. {str(existing[0])!r}); pass --resume "
            "(resume=True) to skip the meshes finished with the same task and options, or "
            "--force (force=True) to redo them")
    out.mkdir(parents=True, exist_ok=True)
    if todo:
        _run_jobs(todo, out, task, options, results, client=client, scheduler=scheduler,
                  workers=workers, memory_limit=memory_limit, retries=retries,
                  thumbnails=thumbnails,
                  thumbnail_size=thumbnail_size, callback=callback,
                  skipped=len(inputs) - len(todo))
    elif callback is not None:
        callback({"event": "start", "dashboard": None, "total": len(inputs), "todo": 0,
                  "skipped": len(inputs), "workers": 0})
    records = [results[rel] for _, rel in inputs]
    if report:
        from meshrepair.batch.report import write_index

        write_index(out, records, task=task, options=options, version=__version__)
    return records


def _run_jobs(todo, out: Path, task: str, options: dict, results: dict, *, client, scheduler,
              workers, memory_limit, retries, thumbnails, thumbnail_size, callback,
              skipped) -> None:
    from distributed import as_completed

    if scheduler is None and workers is None:
        workers = min(os.cpu_count() or 1, len(todo))
    with (connect(scheduler, workers=workers, memory_limit=memory_limit, retries=retries)
          if client is None else nullcontext(client)) as c:
        _single_threaded(c)
        nthreads = max(sum(c.nthreads().values()), 1)
        if callback is not None:
            callback({"event": "start", "dashboard": c.dashboard_link, "total": len(todo)
                      + skipped, "todo": len(todo), "skipped": skipped, "workers": nthreads})
        writer = RecordWriter(out)
        token = secrets.token_hex(4)
        info = {}
        futures = []
        for i, (p, rel, o) in enumerate(todo):
            thumb = str(out / THUMBNAILS / rel) if thumbnails else None
            try:
                size = p.stat().st_size
            except OSError:
                size = 0
            f = c.submit(_job, task, str(p), str(o), options, thumb, thumbnail_size,
                         key=f"meshrepair-{task}-{token}-{i}", pure=False, retries=retries,
                         priority=size)  # big meshes first: shorter tail
            info[f.key] = (p, rel, o)
            futures.append(f)
        counts = {"done": 0, "failed": 0}
        try:
            for f in as_completed(futures):
                p, rel, o = info[f.key]
                try:
                    rec = f.result()
                except Exception as exc:  # KilledWorker: the worker died on every attempt
                    rec = _lost(task, p, o, exc)
                f.release()
                rec = {"rel": rel, **rec, "options": options, "version": __version__,
                       "finished": datetime.datetime.now(datetime.timezone.utc)
                       .isoformat(timespec="seconds")}
                writer.write(rec)
                results[rel] = rec
                counts["done" if rec["status"] == "done" else "failed"] += 1
                if callback is not None:
                    left = len(todo) - counts["done"] - counts["failed"]
                    callback({"event": "mesh", "record": rec, **counts,
                              "running": min(left, nthreads), "total": len(todo)})
        finally:
            writer.close()
            swept = [o for _, _, o in todo]
            if thumbnails:  # a worker killed while writing a thumbnail leaves its temporary too
                swept += [out / THUMBNAILS / f"{rel}.{k}.png" for _, rel, _ in todo
                          for k in ("before", "after")]
            remove_stale_temporaries(swept)

