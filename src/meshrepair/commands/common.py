"""Helpers shared by the CLI sub-commands: safe output paths, writing a result like its input,
progress bars."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import MeshRepairError

MESH_SUFFIXES = (".ply", ".obj", ".off", ".stl")
LOG_SUFFIXES = (".json",)
REPORT_SUFFIXES = (".html", ".htm")
PNG_SUFFIXES = (".png",)


def _same_file(a: Path, b: Path) -> bool:
    """True if ``a`` and ``b`` name the same file (same resolved path, or the same inode via a
    hard link or another spelling)."""
    if a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (or cannot be examined)
        return False


def output_path(out: str | os.PathLike, inputs: list, *, force: bool = False,
                suffixes: tuple[str, ...] = MESH_SUFFIXES, what: str = "output",
                others: list | tuple = ()) -> Path:
    """The one output rule of every command, checked before any work is done.

    An output file must have one of ``suffixes``; it is never one of ``inputs`` (refused even
    with ``force``: main input, template, region mask, log read, ...), never another output of
    the same command (``others``), never an existing file unless ``force`` (and never an
    existing folder, FIFO or device, even with ``force``), and its folder must exist. The file
    itself is then written atomically (:func:`meshrepair.atomic.atomic_write`), with
    ``overwrite=force`` so that a file appearing meanwhile is not replaced either.

    Parameters
    ----------
    out : path
        The output path given by the user.
    inputs : list of path or None
        Every file the command reads (None entries are ignored).
    force : bool
        Allow replacing an existing regular file that is not an input.
    suffixes : tuple of str
        Allowed (lower-case) suffixes; the default means the mesh formats of :mod:`meshrepair.io`.
    what : str
        Name used in messages, e.g. ``"--log"``.
    others : list of path
        Other outputs of the same command, already checked.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MeshRepairError
        With a message naming ``what`` and saying how to fix it.
    """
    from ..atomic import check_writable

    o = Path(out)
    if suffixes is MESH_SUFFIXES:
        from ..io import SUPPORTED_FORMATS

        suffixes = tuple(SUPPORTED_FORMATS)
    if o.suffix.lower() not in suffixes:
        raise MeshRepairError(f"{what} {str(o)!r} must end with one of {', '.join(suffixes)}")
    try:
        for i in [*inputs]:
            if i is None:
                continue
            ip = Path(i)
            if _same_file(ip, o):
                raise MeshRepairError(
                    f"{what} {str(o)!r} is the input file {str(ip)!r}; refusing to overwrite "
                    "the input, choose another output name")
        for other in others:
            if other is not None and _same_file(Path(other), o):
                raise MeshRepairError(f"{what} {str(o)!r} is also another output of this "
                                      "command; give each output its own name")
    except OSError as exc:  # e.g. a name longer than the OS allows
        raise MeshRepairError(f"{what} {str(o)!r}: {exc.strerror or exc}") from None
    try:
        check_writable(o, overwrite=True)
    except MeshRepairError as exc:
        raise MeshRepairError(f"{what}: {exc}") from None
    if o.is_file() and not force:
        raise MeshRepairError(f"{what} {str(o)!r} exists; pass --force to overwrite it")
    return o


def output_folder(folder: str | os.PathLike, names: list[str], inputs: list, *,
                  force: bool = False, what: str = "--outdir") -> list[Path]:
    """The output rule for a command that writes several files into a folder (demo, batch).

    The folder may exist (it is created later, after the checks, by :func:`make_folder`);
    each ``folder / name`` is checked with :func:`output_path` (never an input, never an
    existing file without ``force``). Returns the file paths.
    """
    d = Path(folder)
    try:
        exists, is_dir = d.exists(), d.is_dir()
    except OSError as exc:
        raise MeshRepairError(f"{what} {str(d)!r}: {exc.strerror or exc}") from None
    if exists and not is_dir:
        raise MeshRepairError(f"{what} {str(d)!r} exists and is not a folder")
    paths = [d / n for n in names]
    if exists:
        done: list[Path] = []
        for p in paths:
            try:
                output_path(p, inputs, force=force, suffixes=(p.suffix.lower(),), others=done)
            except MeshRepairError as exc:
                raise MeshRepairError(f"{exc} (from an earlier run? or choose another "
                                      f"{what})") from None
            done.append(p)
    return paths


def make_folder(folder: str | os.PathLike, what: str = "--outdir") -> Path:
    """Create an output folder (and its parents) after :func:`output_folder` checked it."""
    d = Path(folder)
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MeshRepairError(f"cannot create {what} {str(d)!r}: {exc.strerror or exc}") from None
    return d


def optional_output(out: str | os.PathLike | None, inputs: list, *, force: bool,
                    suffixes: tuple[str, ...], what: str, others: list | tuple = ()
                    ) -> Path | None:
    """:func:`output_path` for an optional output option (None stays None)."""
    if out is None or out == "":
        return None
    return output_path(out, inputs, force=force, suffixes=suffixes, what=what, others=others)


def run_outputs(args, inputs: list, *, output: str | None = None,
                suffixes: tuple[str, ...] = MESH_SUFFIXES) -> tuple[Path | None, Path | None,
                                                                     Path | None]:
    """Check a repair command's OUTPUT, ``--log RUN.json`` and ``--report OUT.html`` together
    (before any work): ``(out, log, report)`` paths, None where not given."""
    force = bool(getattr(args, "force", False))
    out = optional_output(output, inputs, force=force, suffixes=suffixes, what="output")
    log = optional_output(getattr(args, "log", None), inputs, force=force,
                          suffixes=LOG_SUFFIXES, what="--log", others=[out])
    rep = optional_output(getattr(args, "report", None), inputs, force=force,
                          suffixes=REPORT_SUFFIXES, what="--report", others=[out, log])
    return out, log, rep


def write_json_log(path: str | os.PathLike | None, data: dict, *, force: bool) -> None:
    """Write a run log atomically (a checked ``--log`` path; nothing if None)."""
    if path is None:
        return
    from ..atomic import write_json

    write_json(path, data, overwrite=force)
    print(f"wrote {path}")


def write_like_input(out: str | os.PathLike, source, result, *, extra: dict | None = None,
                     force: bool = True, template=None, template_map=None) -> None:
    """Write a task's result with everything of its input it does not change.

    The input's attributes are carried over (:func:`meshrepair.io.carry_attributes`: colours,
    texture coordinates, materials, per-face properties; interpolated on new vertices; normals
    recomputed) and the file is stored like the input (binary or ASCII, float32 or float64,
    comments); ``extra`` per-vertex attributes (the command's own masks) are added for a PLY
    output only. What the output format cannot hold is named in one logged warning.
    """
    from ..io import carry_attributes, write_mesh

    like = carry_attributes(source, result, template=template, template_map=template_map)
    extra = extra if Path(out).suffix.lower() == ".ply" else None
    write_mesh(out, like.V, like.F, vertex_attributes=extra or None, like=like,
               overwrite=force)


class ProgressBar:
    """A tqdm progress bar fed by the solver's per-iteration callback.

    The bar is created at the first iteration, so a run that fails during validation prints
    no empty ``0it`` bar before its error message.
    """

    def __init__(self, total: int | None, desc: str, enabled: bool = True):
        self.total, self.desc, self.enabled = total, desc, enabled
        self.bar = None

    def __call__(self, entry: dict) -> None:
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, desc=self.desc, unit="it", leave=False)
        self.bar.update(1)
        self.bar.set_postfix(stage=entry.get("stage", ""), change=f"{entry['rel_change']:.1e}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def add_report_option(p) -> None:
    """The ``--report OUT.html`` option shared by the repair commands."""
    p.add_argument("--report", metavar="OUT.html", default=None,
                   help="also write a self-contained HTML report (renders, masks, metrics, "
                        "convergence plot, parameters, timings)")


def write_run_report(path: str | os.PathLike | None, *, title: str, input_mesh, output_mesh,
                     masks: dict, history: list, parameters: dict, metrics: dict,
                     timings: dict, force: bool = False, **extra) -> None:
    """Write the HTML report of a run if ``path`` is given (see :mod:`meshrepair.report`);
    ``path`` must have been checked with :func:`output_path` (see :func:`run_outputs`)."""
    if not path:
        return
    from ..report import write_report

    if Path(path).suffix.lower() not in REPORT_SUFFIXES:
        raise MeshRepairError(f"--report {str(path)!r} must end with .html")
    params = {k: (v if isinstance(v, (int, float, str, bool, type(None))) else str(v))
              for k, v in parameters.items()}
    write_report(path, title=title, input_mesh=input_mesh, output_mesh=output_mesh, masks=masks,
                 history=history, parameters=params, metrics=metrics, timings=timings,
                 overwrite=force, **extra)  # extra: holes, highlight, regions (write_report)
    print(f"wrote {path}")
