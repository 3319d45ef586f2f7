"""Helpers shared by the CLI sub-commands: safe output paths, progress bars."""

from __future__ import annotations

import os
from pathlib import Path

from meshrepair.errors import MeshRepairError
from meshrepair.io.outputs import (  # noqa: F401  (re-exported: the commands' output rule)
    LOG_SUFFIXES,
    MESH_SUFFIXES,
    PNG_SUFFIXES,
    REPORT_SUFFIXES,
    _same_file,
    output_path,
)


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


def _suffix_list(suffixes: tuple[str, ...]) -> tuple[str, ...]:
    if suffixes is MESH_SUFFIXES:
        from meshrepair.io import SUPPORTED_FORMATS

        return tuple(SUPPORTED_FORMATS)
    return suffixes


def optional_output(out: str | os.PathLike | None, inputs: list, *, force: bool,
                    suffixes: tuple[str, ...], what: str, others: list | tuple = ()
                    ) -> Path | None:
    """:func:`output_path` for an optional output option (None stays None; an empty name is
    refused, not taken as "no output": the work would run and have nowhere to go)."""
    if out is None:
        return None
    if str(out).strip() == "":
        raise MeshRepairError(f"{what} is an empty name: give a file name ending with one of "
                              f"{', '.join(_suffix_list(suffixes))}"
                              + (", or leave the option out" if what.startswith("-") else ""))
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
    from meshrepair.atomic import write_json

    write_json(path, data, overwrite=force)
    print(f"wrote {path}")


class ProgressBar:
    """A tqdm progress bar fed by the solver's per-iteration callback.

    The bar is created at the first iteration, so a run that fails during validation prints
    no empty ``0it`` bar before its error message. A task may run the solver more than once
    (``denoise`` solves again after a check of its first result): an entry whose ``iter``
    does not follow the previous one starts a new pass, and the bar starts again from 0 under
    ``desc (pass N)``, so that it counts the iterations of the pass the summary reports.
    ``passes`` and ``count`` (iterations of all passes) are kept for that summary. ``total`` is
    the first pass's length, ``later`` (default ``total``) that of the passes after it.
    """

    def __init__(self, total: int | None, desc: str, enabled: bool = True, *,
                 later: int | None = None):
        self.total, self.desc, self.enabled = total, desc, enabled
        self.later = total if later is None else later  # the total of the passes after the first
        self.bar = None
        self.passes = 0
        self.count = 0
        self._last = None

    def __call__(self, entry: dict) -> None:
        it = entry.get("iter")
        new_pass = self.passes == 0 or it is None or self._last is None or it <= self._last
        self._last = it
        self.count += 1
        if new_pass:
            self.passes += 1
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, desc=self.desc, unit="it", leave=False)
        elif new_pass:
            self.bar.reset(total=self.later)
            self.bar.set_description(f"{self.desc} (pass {self.passes})")
        self.bar.update(1)
        self.bar.set_postfix(stage=entry.get("stage", ""), change=f"{entry['rel_change']:.1e}")

    def passes_note(self) -> str:
        """``"; the last of 2 solver passes, 194 iterations in all"`` when there were several
        passes, else ``""`` (for the command's summary line)."""
        if self.passes <= 1:
            return ""
        return f"; the last of {self.passes} solver passes, {self.count} iterations in all"

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def angle_degrees(text: str) -> float:
    """argparse type of a dihedral threshold: a number of degrees in (0, 180)
    (:func:`meshrepair.options.check_angle`)."""
    import argparse

    from meshrepair.options import check_angle

    try:
        return check_angle("the threshold", float(text))
    except (ValueError, MeshRepairError):
        raise argparse.ArgumentTypeError(f"must be an angle in degrees in (0, 180), got "
                                         f"{text!r}") from None


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
    from meshrepair.report.page import write_report

    if Path(path).suffix.lower() not in REPORT_SUFFIXES:
        raise MeshRepairError(f"--report {str(path)!r} must end with .html")
    params = {k: (v if isinstance(v, (int, float, str, bool, type(None))) else str(v))
              for k, v in parameters.items()}
    write_report(path, title=title, input_mesh=input_mesh, output_mesh=output_mesh, masks=masks,
                 history=history, parameters=params, metrics=metrics, timings=timings,
                 overwrite=force, **extra)  # extra: holes, highlight, regions (write_report)
    print(f"wrote {path}")
