"""One mesh, one task: read a mesh file, repair it with the public function, write the result
atomically and return a small JSON-able record.

This is what :mod:`meshrepair.batch` runs on every Dask worker (it adds only the worker's
address): inputs and outputs are file paths, the record is a dict of plain values, never a
mesh. Nothing here knows about Dask, so a job can be run and tested in-process.

A job never raises for a bad mesh: any exception (unreadable file, invalid mesh, a task that
refuses the input) becomes ``status="failed"`` with the error message. The output is written by
:func:`meshrepair.io.write_mesh` (temporary file in the target folder, then rename), so it is
either absent or complete; the output path is checked by the commands' output rule
(:func:`meshrepair.io.outputs.output_path`: never an input file). The task options mean
exactly what the single commands' options mean (the commands build them with
``denoise_options``, ``fill_options``, ``inpaint_options`` and ``complete_options``), and the
written file is the one the single command writes (same vertex attributes).

Options that name files (``region``, ``template``, ``template_region``, ``transform``) may hold
``{stem}``, ``{name}``, ``{parent}`` or ``{path}``, replaced by the input file's stem, name,
folder and full path, e.g. ``region="{parent}/{stem}.region.txt"``.
"""

from __future__ import annotations

import inspect
import json
import logging
import os
import socket
import time
import traceback
from pathlib import Path

import numpy as np

from meshrepair.errors import MeshRepairError

log = logging.getLogger(__name__)

TASKS = ("denoise", "fill", "inpaint", "complete")

#: thread counts of the numeric libraries on a worker: one mesh per single-threaded process
THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "NUMBA_NUM_THREADS": "1", "VECLIB_MAXIMUM_THREADS": "1",
              "NUMEXPR_NUM_THREADS": "1"}

#: options that are not keyword arguments of the task's public function
_EXTRA = {"denoise": ("save_mask",), "fill": (), "inpaint": ("region", "attribute"),
          "complete": ("template", "region", "hole", "template_region", "transform")}
_NOT_OPTIONS = {"V", "F", "callback", "region_vertices", "stages"}
_FILE_OPTIONS = ("region", "template", "template_region", "transform")


def _public(task: str):
    from meshrepair import complete, denoise, fill_holes, inpaint

    return {"denoise": denoise, "fill": fill_holes, "inpaint": inpaint,
            "complete": complete}[task]


def task_option_names(task: str) -> tuple[str, ...]:
    """The option names a task accepts: the public function's keyword arguments plus the
    file-level ones (``save_mask``; inpaint ``region``, ``attribute``; complete ``template``,
    ``region``, ``hole``, ``template_region``, ``transform``)."""
    if task not in TASKS:
        raise MeshRepairError(f"unknown task {task!r}: choose one of {', '.join(TASKS)}")
    names = [n for n in inspect.signature(_public(task)).parameters if n not in _NOT_OPTIONS]
    return tuple(dict.fromkeys([*names, *_EXTRA[task]]))


def check_options(task: str, options: dict) -> dict:
    """Validate option names and make the options plain JSON values (tuples become lists),
    so that they travel to workers and compare equal when a batch is resumed.

    Raises
    ------
    MeshRepairError
        Unknown task, unknown option name, or a value that is not JSON (numbers, strings,
        booleans, None, lists, dicts).
    """
    allowed = task_option_names(task)
    bad = sorted(set(options) - set(allowed))
    if bad:
        raise MeshRepairError(f"{task} has no option {', '.join(map(repr, bad))}; its options "
                              f"are {', '.join(allowed)}")
    try:
        plain = json.loads(json.dumps(options, sort_keys=True, allow_nan=False))
    except (TypeError, ValueError) as exc:
        raise MeshRepairError(f"{task} options must be plain values (numbers, strings, lists) "
                              f"that a record can store: {exc}") from None
    _check_values(task, plain)
    return plain


def _check_values(task: str, options: dict) -> None:
    """The values of the solver options, checked as the task's function checks them, before a
    worker starts (a bad value would otherwise fail every mesh of the collection)."""
    fn = _public(task)
    given = {k: v for k, v in options.items() if k not in _EXTRA[task]}
    args = {n: p.default for n, p in inspect.signature(fn).parameters.items()
            if p.default is not inspect.Parameter.empty}
    args.update(given)
    if task == "denoise":
        from meshrepair.denoise.checks import _checked

        _checked(**{n: args[n] for n in inspect.signature(_checked).parameters})
    elif task in ("fill", "inpaint"):
        from meshrepair.fill.options import _check_options, _solve_options
        from meshrepair.holes.detect import check_max_hole_size
        from meshrepair.options import check_bool

        _check_options(_solve_options(args))
        check_bool("keep_border", args["keep_border"])
        check_max_hole_size(args.get("max_hole_size"))


def _expand(value, inp: Path):
    if not isinstance(value, str):
        return value
    try:
        return value.format(stem=inp.stem, name=inp.name, parent=str(inp.parent), path=str(inp))
    except (KeyError, IndexError, ValueError) as exc:
        raise MeshRepairError(f"file option {value!r}: unknown placeholder {exc} (use {{stem}}, "
                              "{name}, {parent} or {path})") from None


# ------------------------------------------------------------------------------------------
# the four tasks: (input mesh, output (V, F), metrics); each calls the public function


def _solved(res):
    """``res`` unless its solve was interrupted (Ctrl-C): a partial iterate is not written."""
    if getattr(res, "stop_reason", "") == "interrupted":
        raise MeshRepairError("interrupted: nothing written for this mesh")
    return res


def _denoise(m, out: Path, opts: dict):
    from meshrepair import denoise
    from meshrepair.io import write_like_input

    save_mask = opts.pop("save_mask", False)
    r = _solved(denoise(m.V, m.F, **opts))
    attrs = {}
    if save_mask:
        sharp_v = np.zeros(len(r.V), np.uint8)
        sharp_v[r.edges[r.M_E].ravel()] = 1
        attrs["sharp"] = sharp_v
    write_like_input(out, m, r, extra=attrs)
    return r.V, r.F, {"noise_estimate": float(r.noise_estimate),
                      "lambda": float(r.params["lam"]), "iterations": int(r.iterations),
                      "stop_reason": r.stop_reason, "sharp_edges": int(r.M_E.sum())}


def _fill_metrics(res) -> dict:
    skipped = [f"hole {h.index}: {h.reason}" for h in res.holes if h.status != "filled"]
    return {"holes_found": len(res.holes), "holes_filled": int(res.n_filled),
            "holes_skipped": int(res.n_skipped), "new_vertices": int(len(res.new_vertices)),
            "new_faces": int(len(res.new_faces)), "skipped": skipped[:20]}


def _fill(m, out: Path, opts: dict):
    from meshrepair import fill_holes
    from meshrepair.io import write_like_input

    res = _solved(fill_holes(m.V, m.F, **opts))
    write_like_input(out, m, res, extra={"filled": res.filled_mask})
    return res.V, res.F, _fill_metrics(res)


def _inpaint(m, out: Path, opts: dict):
    from meshrepair import inpaint
    from meshrepair.fill.region import resolve_region
    from meshrepair.io import write_like_input

    region = resolve_region(opts.pop("region", None), opts.pop("attribute", None), len(m.V))
    res = _solved(inpaint(m.V, m.F, region, **opts))
    write_like_input(out, m, res, extra={"filled": res.filled_mask})
    return res.V, res.F, _fill_metrics(res)


def _complete(m, out: Path, opts: dict):
    from meshrepair import complete, read_mesh
    from meshrepair.complete.files import (
        complete_arguments,
        output_attributes,
        template_vertex_map,
    )
    from meshrepair.io import write_like_input

    tpath = opts.pop("template", None)
    if tpath is None and not opts.get("mirror"):
        raise MeshRepairError("complete needs a template mesh (--template FILE) or --mirror")
    kw = {k: opts.pop(k, None) for k in ("region", "hole", "template_region")}
    tmesh = read_mesh(tpath) if tpath is not None else None
    template, kw = complete_arguments(m, tmesh, {**kw, **opts})
    res = _solved(complete(m.V, m.F, template=template, **kw))
    write_like_input(out, m, res, extra=output_attributes(res, out), template=tmesh,
                     template_map=template_vertex_map(tmesh, template, res))
    c = res.correspondence
    return res.V, res.F, {"seam_vertices": int(c["n_seam"]),
                          "rms_boundary_before": float(c["rms_before"]),
                          "rms_boundary_after": float(c["rms_after"]),
                          "strip_vertices": int(len(res.strip_vertices)),
                          "iterations": int(res.iterations)}


_RUN = {"denoise": _denoise, "fill": _fill, "inpaint": _inpaint, "complete": _complete}


# ------------------------------------------------------------------------------------------
# process probes


def _reset_peak_rss() -> bool:
    try:  # Linux: reset VmHWM so that it measures this job only
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


def _status_mb(key: str) -> float | None:
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(key):
                    return round(int(line.split()[1]) / 1024, 1)
    except OSError:
        pass
    return None


def _peak_rss_mb() -> float | None:
    peak = _status_mb("VmHWM:")
    if peak is None:
        import resource

        r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        peak = round(r / 1024, 1)  # lifetime peak (KiB on Linux)
    return peak


def thread_counts() -> dict:
    """Threads the numeric libraries of this process would use (BLAS/OpenMP pools, numba)."""
    out: dict = {}
    try:
        from threadpoolctl import threadpool_info

        out["blas"] = max((int(i.get("num_threads", 1)) for i in threadpool_info()), default=1)
    except Exception:  # pragma: no cover - threadpoolctl is a dependency
        out["blas"] = None
    try:
        import numba

        out["numba"] = int(numba.get_num_threads())
    except Exception:  # pragma: no cover - numba is a dependency
        out["numba"] = None
    return out


class _WarningsCollector(logging.Handler):
    """Keeps the library's warnings during a job (e.g. pinched vertices) for its record."""

    def __init__(self, limit: int = 20):
        super().__init__(logging.WARNING)
        self.messages: list[str] = []
        self.limit = limit

    def emit(self, record: logging.LogRecord) -> None:
        if len(self.messages) < self.limit:
            self.messages.append(record.getMessage())


def _thumbnails(base: str, before, after, size: int) -> dict:
    from meshrepair.render import render_mesh, save_png

    out = {}
    bounds = np.array([before[0].min(axis=0), before[0].max(axis=0)])
    for name, mesh in (("before", before), ("after", after)):
        if mesh is None:
            continue
        img = render_mesh(mesh[0], mesh[1], width=size, height=size, colorbar=False,
                          fit_bounds=bounds, azimuth=35.0, elevation=25.0)
        p = Path(f"{base}.{name}.png")
        save_png(p, img)  # atomic (meshrepair.atomic)
        out[name] = str(p)
    return out


# ------------------------------------------------------------------------------------------


def run_job(task: str, input: str, output: str, options: dict, *,
            thumbnails: str | None = None, thumbnail_size: int = 160) -> dict:
    """Repair one mesh file; never raises for a bad mesh.

    Parameters
    ----------
    task : {"denoise", "fill", "inpaint", "complete"}
    input, output : str
        Mesh files; the output's folder is created; it is never the input.
    options : dict
        The task's options (:func:`task_option_names`), as made by :func:`check_options`.
    thumbnails : str, optional
        Base path of the before/after PNG thumbnails (``BASE.before.png``, ``BASE.after.png``).

    Returns
    -------
    dict
        ``status`` ("done" or "failed"), ``error``, ``error_type``, ``seconds`` (wall),
        ``cpu_seconds`` (CPU time of the process: below ``seconds`` when the machine is busy),
        ``peak_rss_mb`` (resident high-water mark of the process during the job), ``vertices``,
        ``faces``, ``out_vertices``, ``out_faces``, ``metrics`` (the task's), ``warnings`` (the
        library's warnings during the job), ``threads``,
        ``pid``, ``host``, ``thumbnails`` and the input's ``input_size`` and ``input_mtime_ns``.
    """
    from threadpoolctl import threadpool_limits

    from meshrepair.io import read_mesh
    from meshrepair.io.outputs import output_path

    t0, c0 = time.perf_counter(), time.process_time()
    hwm = _reset_peak_rss()
    rec: dict = {"task": task, "input": str(input), "output": str(output), "status": "failed",
                 "error": None, "error_type": None, "vertices": None, "faces": None,
                 "out_vertices": None, "out_faces": None, "metrics": {},
                 "threads": thread_counts(), "pid": os.getpid(), "host": socket.gethostname(),
                 "rss_start_mb": _status_mb("VmRSS:"), "thumbnails": {}}
    inp, out = Path(input), Path(output)
    try:
        st = inp.stat()
        rec["input_size"], rec["input_mtime_ns"] = st.st_size, st.st_mtime_ns
    except OSError:
        pass
    before = after = None
    warnings = _WarningsCollector()
    logging.getLogger("meshrepair").addHandler(warnings)
    try:
        if task not in _RUN:
            raise MeshRepairError(f"unknown task {task!r}: choose one of {', '.join(TASKS)}")
        opts = {k: _expand(v, inp) if k in _FILE_OPTIONS else v for k, v in options.items()}
        files = [opts.get(k) for k in _FILE_OPTIONS if isinstance(opts.get(k), str)]
        with threadpool_limits(1):
            m = read_mesh(inp)
            before = (m.V, m.F)
            rec["vertices"], rec["faces"] = int(len(m.V)), int(len(m.F))
            out.parent.mkdir(parents=True, exist_ok=True)
            output_path(out, [inp, *files], force=True)
            V, F, metrics = _RUN[task](m, out, dict(opts))
        after = (V, F)
        rec.update(status="done", out_vertices=int(len(V)), out_faces=int(len(F)),
                   metrics=metrics)
    except MeshRepairError as exc:
        rec.update(error=str(exc), error_type="MeshRepairError")
    except Exception as exc:  # a bad mesh never stops a batch: record what went wrong
        where = traceback.extract_tb(exc.__traceback__)[-1]
        rec.update(error=f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:"
                         f"{where.lineno})", error_type=type(exc).__name__)
        log.debug("job %s failed", input, exc_info=True)
    finally:
        logging.getLogger("meshrepair").removeHandler(warnings)
    rec["warnings"] = warnings.messages
    rec["seconds"] = round(time.perf_counter() - t0, 4)
    rec["cpu_seconds"] = round(time.process_time() - c0, 4)
    rec["peak_rss_mb"] = _peak_rss_mb()
    rec["peak_rss_scope"] = "job" if hwm else "process"
    if thumbnails and before is not None:
        t1 = time.perf_counter()
        try:
            rec["thumbnails"] = _thumbnails(thumbnails, before, after, thumbnail_size)
        except Exception as exc:  # a picture is a bonus; never fail a repaired mesh on it
            rec["thumbnail_error"] = f"{type(exc).__name__}: {exc}"
        rec["thumbnail_seconds"] = round(time.perf_counter() - t1, 4)
    return rec
