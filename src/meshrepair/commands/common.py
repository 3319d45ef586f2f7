"""Helpers shared by the CLI sub-commands: safe output paths, progress bars."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import MeshRepairError

MESH_SUFFIXES = (".ply", ".obj", ".off", ".stl")


def output_path(out: str | os.PathLike, inputs: list, *, force: bool = False,
                suffixes: tuple[str, ...] = MESH_SUFFIXES) -> Path:
    """Validate an output path: known suffix, never an input file, no silent overwrite.

    Raises
    ------
    MeshRepairError
        If ``out`` has an unknown suffix, is one of ``inputs`` (always refused, even with
        ``force``), or exists and ``force`` is False.
    """
    o = Path(out)
    if suffixes is MESH_SUFFIXES:
        from ..io import SUPPORTED_FORMATS

        suffixes = tuple(SUPPORTED_FORMATS)
    if o.suffix.lower() not in suffixes:
        raise MeshRepairError(f"output {str(o)!r} must end with one of {', '.join(suffixes)}")
    for i in inputs:
        if i is None:
            continue
        ip = Path(i)
        if ip.resolve() == o.resolve() or (o.exists() and ip.exists() and os.path.samefile(ip, o)):
            raise MeshRepairError(
                f"output {str(o)!r} is the input file {str(ip)!r}; refusing to overwrite the "
                "input, choose another output name")
    if o.exists() and not force:
        raise MeshRepairError(f"output {str(o)!r} exists; pass --force to overwrite it")
    if not o.parent.is_dir():
        raise MeshRepairError(f"the folder of the output {str(o)!r} does not exist")
    return o


class ProgressBar:
    """A tqdm progress bar fed by the solver's per-iteration callback."""

    def __init__(self, total: int | None, desc: str, enabled: bool = True):
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, unit="it", disable=not enabled, leave=False)

    def __call__(self, entry: dict) -> None:
        self.bar.update(1)
        self.bar.set_postfix(stage=entry.get("stage", ""), change=f"{entry['rel_change']:.1e}")

    def close(self) -> None:
        self.bar.close()


def add_report_option(p) -> None:
    """The ``--report OUT.html`` option shared by the repair commands."""
    p.add_argument("--report", metavar="OUT.html", default=None,
                   help="also write a self-contained HTML report (renders, masks, metrics, "
                        "convergence plot, parameters, timings)")


def write_run_report(path: str | None, *, title: str, input_mesh, output_mesh, masks: dict,
                     history: list, parameters: dict, metrics: dict, timings: dict,
                     **extra) -> None:
    """Write the HTML report of a run if ``path`` is given (see :mod:`meshrepair.report`)."""
    if not path:
        return
    from ..report import write_report

    if Path(path).suffix.lower() not in (".html", ".htm"):
        raise MeshRepairError(f"--report {path!r} must end with .html")
    params = {k: (v if isinstance(v, (int, float, str, bool, type(None))) else str(v))
              for k, v in parameters.items()}
    write_report(path, title=title, input_mesh=input_mesh, output_mesh=output_mesh, masks=masks,
                 history=history, parameters=params, metrics=metrics, timings=timings,
                 **extra)  # extra: holes, highlight, regions, ... (see write_report)
    print(f"wrote {path}")
