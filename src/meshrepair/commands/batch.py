"""``meshrepair batch``: repair a whole collection on Dask (local cores, or a cluster).

Examples
--------
``meshrepair batch scans/ repaired/ --task denoise``
``meshrepair batch 'scans/**/*.ply' repaired/ --task fill --keep-border --workers 4``
``meshrepair batch list.txt repaired/ --task denoise --scheduler tcp://head:8786 --resume``

The task options are the single commands' own option definitions (``add_denoise_options``,
``add_fill_options``, ``add_inpaint_options``, ``add_complete_options``), turned into the public
functions' arguments by the same ``*_options`` functions, so an option means in a batch what it
means for one mesh. Options two tasks share (``--th``, ``--denoise``, ``--region``, ...) are
listed once, under the first task that has them.
"""

from __future__ import annotations

import argparse
import logging

from meshrepair.batch.jobs import TASKS
from meshrepair.errors import MeshRepairError


class _Once:
    """An argparse group facade for one task's options: an option string an earlier task
    already defined is reused (the definitions must agree), and mutually exclusive groups are
    flattened (``batch`` checks them per task, since they are required for one task only)."""

    def __init__(self, group, task: str, seen: dict, dests: dict):
        self.group, self.task, self.seen, self.dests = group, task, seen, dests

    def add_argument(self, *flags, **kw):
        if flags[0] in self.seen:
            act = self.seen[flags[0]]
            if act.dest != flags[0].lstrip("-").replace("-", "_") or act.default != kw.get(
                    "default", False if kw.get("action") == "store_true" else None):
                raise AssertionError(f"{flags[0]} is defined differently by two tasks")
        else:
            act = self.group.add_argument(*flags, **kw)
            for f in flags:
                self.seen[f] = act
        self.dests[self.task].add(act.dest)
        return act

    def add_mutually_exclusive_group(self, required: bool = False):
        return self


def _add_task_options(p: argparse.ArgumentParser) -> dict:
    from meshrepair.commands.complete import add_complete_options
    from meshrepair.commands.denoise import add_denoise_options
    from meshrepair.commands.fill import add_fill_options, add_inpaint_options, add_solve_options

    seen: dict = {}
    dests: dict = {t: set() for t in TASKS}

    def complete(q):
        q.add_argument("--template", metavar="FILE", default=None,
                       help="complete: the template patch (the single command's TEMPLATE)")
        add_complete_options(q, required=False)

    adders = {"denoise": add_denoise_options,
              "fill": lambda q: (add_fill_options(q), add_solve_options(q)),
              "inpaint": lambda q: (add_inpaint_options(q, required=False),
                                    add_solve_options(q)),
              "complete": complete}
    for task in TASKS:
        g = p.add_argument_group(f"{task} options (as for 'meshrepair {task}')")
        adders[task](_Once(g, task, seen, dests))
    flags = {}
    for f, act in seen.items():
        flags.setdefault(act.dest, f)
    return {"dests": dests, "flags": flags,
            "defaults": {act.dest: act.default for act in seen.values()}}


def _one_of(args, names: tuple[str, ...], task: str) -> None:
    given = [n for n in names if getattr(args, n) is not None]
    if len(given) != 1:
        opts = ", ".join("--" + n.replace("_", "-") for n in names)
        raise MeshRepairError(f"--task {task} needs exactly one of {opts}"
                              + (f" (got {len(given)})" if given else ""))


def task_options(args: argparse.Namespace) -> dict:
    """The options of ``args.task`` for :func:`meshrepair.batch.orchestrate.run`; refuses options
    of other
    tasks (e.g. ``--keep-border`` with ``--task denoise``)."""
    from meshrepair.commands.complete import complete_options
    from meshrepair.commands.denoise import denoise_options
    from meshrepair.commands.fill import fill_options, inpaint_options

    spec = args._batch_options
    mine = spec["dests"][args.task]
    foreign = [spec["flags"][d] for d, default in spec["defaults"].items()
               if d not in mine and getattr(args, d) != default]
    if foreign:
        raise MeshRepairError(f"{', '.join(sorted(foreign))} not an option of --task "
                              f"{args.task}; see 'meshrepair batch --help'")
    if args.task == "denoise":
        return denoise_options(args)
    if args.task == "fill":
        return fill_options(args)
    if args.task == "inpaint":
        _one_of(args, ("region", "sphere", "box"), "inpaint")
        return inpaint_options(args)
    _one_of(args, ("region", "hole"), "complete")
    if (args.template is None) == (not args.mirror):
        raise MeshRepairError("--task complete needs --template FILE (the template patch) or "
                              "--mirror (the template from the mesh's symmetry), not both")
    return {"template": args.template, **complete_options(args)}


def run_batch(args: argparse.Namespace) -> int:
    """Handler of ``meshrepair batch``; returns 0, or 1 if a mesh failed."""
    from tqdm import tqdm

    import meshrepair.batch.orchestrate as batch
    options = task_options(args)
    state: dict = {}

    def progress(ev: dict) -> None:
        if ev["event"] == "start":
            if ev["dashboard"]:
                print(f"Dask dashboard: {ev['dashboard']} ({ev['workers']} worker threads)")
            if ev["skipped"]:
                print(f"--resume: {ev['skipped']} of {ev['total']} meshes already done, skipped")
            state["bar"] = tqdm(total=ev["todo"], desc=args.task, unit="mesh",
                                disable=args.quiet)
            return
        bar = state["bar"]
        bar.set_postfix(done=ev["done"], failed=ev["failed"], running=ev["running"],
                        refresh=False)
        bar.update(1)

    if not getattr(args, "verbose", 0):  # Dask logs its cluster's life at INFO level
        import distributed  # noqa: F401 - configures its loggers on import; then quieten them

        logging.getLogger("distributed").setLevel(logging.WARNING)
    try:
        records = batch.run(args.input, args.output, task=args.task, scheduler=args.scheduler,
                            workers=args.workers, memory_limit=args.memory_limit,
                            retries=args.retries, resume=args.resume, force=args.force,
                            pattern=args.pattern, thumbnails=not args.no_thumbnails,
                            callback=progress, **options)
    finally:
        if "bar" in state:
            state["bar"].close()
    failed = [r for r in records if r["status"] != "done"]
    resumed = sum(bool(r.get("resumed")) for r in records)
    print(f"{len(records) - len(failed)} of {len(records)} meshes repaired"
          + (f" ({resumed} resumed)" if resumed else "") + f", {len(failed)} failed")
    for r in failed[:10]:
        print(f"  failed {r['rel']}: {r['error']}")
    if len(failed) > 10:
        print(f"  ... and {len(failed) - 10} more (see {args.output}/batch.jsonl)")
    print(f"wrote {args.output}/batch.jsonl and {args.output}/index.html")
    return 1 if failed else 0


def _positive_int(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return n


def register(subparsers) -> None:
    """Add the ``batch`` sub-command to an argparse ``subparsers`` object."""
    p = subparsers.add_parser(
        "batch", help="repair a whole collection on Dask (this machine's cores or a cluster)",
        description="Repair every mesh of IN with one task, one mesh per single-threaded Dask "
        "worker process: a local cluster by default, a running Dask scheduler with "
        "--scheduler. OUT mirrors IN's layout and gets batch.jsonl (one record per mesh) and "
        "index.html (thumbnails, status, metrics; failures first). A bad mesh is recorded "
        "and never stops the batch; exit status 1 if any mesh failed. See docs/batch.md.",
        epilog="Task options mean what they mean for the single command; an option two tasks "
        "share (--th, --denoise, --initial, --no-refine, --region) is listed once, under the "
        "first; --region is a vertex mask for inpaint and the faces to replace for complete, as "
        "in the single commands. File options may use {stem}, {name}, {parent} or {path} of "
        "each input, e.g. --region '{parent}/{stem}.mask.npy'.")
    p.add_argument("input", metavar="IN",
                   help="folder (searched recursively), quoted glob ('scans/**/*.ply') or a "
                   "text file listing mesh paths")
    p.add_argument("output", metavar="OUT", help="output folder (never the input folder)")
    p.add_argument("--task", required=True, choices=TASKS, help="the repair to run")
    g = p.add_argument_group("batch options")
    g.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                   help="local worker processes (default: the number of cores)")
    g.add_argument("--memory-limit", default=None, metavar="4GB",
                   help="per local worker; above it a worker is restarted and its mesh retried "
                   "(default: the machine's memory shared among the workers)")
    g.add_argument("--scheduler", default=None, metavar="tcp://host:8786",
                   help="run on this running Dask scheduler's workers instead")
    g.add_argument("--resume", action="store_true",
                   help="skip meshes already repaired with the same task, options and version")
    g.add_argument("--force", action="store_true", help="overwrite existing outputs")
    g.add_argument("--pattern", default=None, metavar="'*.ply'",
                   help="file-name pattern in a folder (default: every .ply .obj .off .stl)")
    g.add_argument("--retries", type=int, default=2, metavar="K",
                   help="local cluster: re-runs of a mesh whose worker died (default 2)")
    g.add_argument("--no-thumbnails", action="store_true",
                   help="no before/after pictures in index.html")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    spec = _add_task_options(p)
    p.set_defaults(func=run_batch, _batch_options=spec)
