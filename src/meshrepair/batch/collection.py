"""A collection of mesh files for :mod:`meshrepair.batch`: finding the inputs, mirroring their
layout under the output folder, and the run's records file ``OUT/batch.jsonl``.

Inputs are given as a folder (searched recursively), a glob pattern (``scans/**/*.ply``), a text
file listing paths (one per line, ``#`` comments, relative paths relative to the list file), a
single mesh file, or a Python list of paths. Each input gets a relative path ``rel`` (relative to
the folder, to the fixed part of the glob, or to the common folder of the listed files) and its
output is ``OUT/rel``: the output tree mirrors the input tree.

``batch.jsonl`` holds one JSON record per line, appended as meshes finish (a line is written
and flushed at once, so an interrupted run loses at most the line being written, which the
reader skips). The latest record of a mesh wins. A record lets a resumed run skip a mesh when
it says ``done`` for the same task, options, meshrepair version and input (size and mtime) and
its output file exists (:func:`is_done`).
"""

from __future__ import annotations

import fnmatch
import glob
import json
import logging
import os
from pathlib import Path

from meshrepair.atomic import _TMP_NAME_MAX
from meshrepair.errors import MeshRepairError

log = logging.getLogger(__name__)

RECORDS = "batch.jsonl"
INDEX = "index.html"
THUMBNAILS = "thumbnails"
_GLOB_CHARS = set("*?[")


def _mesh_suffixes() -> tuple[str, ...]:
    from meshrepair.io import SUPPORTED_FORMATS

    return tuple(SUPPORTED_FORMATS)


def _is_inside(p: Path, folder: Path | None) -> bool:
    if folder is None:
        return False
    try:
        p.resolve().relative_to(folder.resolve())
        return True
    except ValueError:
        return False


def _matches(p: Path, pattern: str | None) -> bool:
    if p.name.startswith("."):  # hidden files and the temporary files of atomic writes
        return False
    if pattern is None:
        return p.suffix.lower() in _mesh_suffixes()
    return fnmatch.fnmatch(p.name, pattern)


def _with_rel(paths: list[Path], root: Path) -> list[tuple[Path, str]]:
    out, seen = [], {}
    for p in paths:
        rel = Path(os.path.relpath(p.resolve(), root.resolve())).as_posix()
        if rel in seen:
            if seen[rel] == p.resolve():
                continue  # listed twice
            raise MeshRepairError(f"two inputs map to the same output {rel!r}: {seen[rel]} and "
                                  f"{p}; rename one")
        seen[rel] = p.resolve()
        out.append((p, rel))
    return out


def _common_root(paths: list[Path]) -> Path:
    parents = [str(p.resolve().parent) for p in paths]
    return Path(os.path.commonpath(parents)) if parents else Path(".")


def collect_inputs(spec, *, pattern: str | None = None, exclude: str | os.PathLike | None = None
                   ) -> list[tuple[Path, str]]:
    """The inputs of a batch as ``(path, rel)`` pairs, sorted by ``rel``.

    Parameters
    ----------
    spec : folder, glob pattern, list file, mesh file, or a list of paths
    pattern : str, optional
        File-name pattern (``fnmatch``, e.g. ``"*.ply"``) for a folder; default: every file with a
        mesh suffix (.ply .obj .off .stl, any case). Hidden files are skipped.
    exclude : folder, optional
        Files inside it are skipped (the batch's own output folder inside the input folder).

    Raises
    ------
    MeshRepairError
        If the folder, list file or file does not exist, or nothing matches.
    """
    ex = Path(exclude) if exclude is not None else None
    if isinstance(spec, (list, tuple)):
        paths = [Path(p) for p in spec]
        if not paths:
            raise MeshRepairError("no input meshes given (an empty list)")
        return _with_rel(paths, _common_root(paths))
    s = str(spec)
    p = Path(s)
    if p.is_dir():
        found = sorted(q for q in p.rglob("*") if q.is_file() and _matches(q, pattern)
                       and not _is_inside(q, ex))
        what = f"folder {s!r}" + (f" (pattern {pattern!r})" if pattern else "")
        if not found:
            raise MeshRepairError(f"no mesh files in {what}; check the folder or --pattern")
        return _with_rel(found, p)
    if _GLOB_CHARS & set(s) and not p.exists():
        found = sorted(Path(q) for q in glob.glob(s, recursive=True))
        found = [q for q in found if q.is_file() and not q.name.startswith(".")
                 and not _is_inside(q, ex) and (pattern is None or _matches(q, pattern))]
        if not found:
            raise MeshRepairError(f"the pattern {s!r} matches no file")
        fixed = []
        for part in Path(s).parts:
            if _GLOB_CHARS & set(part):
                break
            fixed.append(part)
        return _with_rel(found, Path(*fixed) if fixed else Path("."))
    if not p.is_file():
        raise MeshRepairError(f"input {s!r} is neither a folder, a glob pattern nor a file")
    if p.suffix.lower() in _mesh_suffixes():
        return _with_rel([p], p.parent)
    try:
        lines = p.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise MeshRepairError(f"cannot read the list file {s!r} as text: {exc}") from None
    paths = []
    for line in lines:
        line = line.split("#", 1)[0].strip()
        if line:
            q = Path(line)
            paths.append(q if q.is_absolute() else p.parent / q)
    if not paths:
        raise MeshRepairError(f"the list file {s!r} lists no path")
    return _with_rel(paths, _common_root(paths))


# ------------------------------------------------------------------------------------------
# records


def read_records(out_dir: str | os.PathLike) -> dict[str, dict]:
    """The latest record per ``rel`` in ``OUT/batch.jsonl`` (empty if there is none)."""
    path = Path(out_dir) / RECORDS
    latest: dict[str, dict] = {}
    if not path.is_file():
        return latest
    with open(path, encoding="utf-8") as fh:
        for n, line in enumerate(fh, 1):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except ValueError:
                log.warning("%s line %d is not a JSON record (interrupted write?); ignored",
                            path, n)
                continue
            if isinstance(rec, dict) and "rel" in rec:
                latest[rec["rel"]] = rec
    return latest


class RecordWriter:
    """Appends records to ``OUT/batch.jsonl``, one line each, flushed and synced to disk."""

    def __init__(self, out_dir: str | os.PathLike):
        self.path = Path(out_dir) / RECORDS
        self._fh = open(self.path, "a", encoding="utf-8")

    def write(self, rec: dict) -> None:
        self._fh.write(json.dumps(rec, default=str) + "\n")
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def close(self) -> None:
        self._fh.close()


def is_done(rec: dict | None, *, task: str, options: dict, version: str, input: Path,
            output: Path) -> bool:
    """True if ``rec`` says the mesh was repaired with the same task, options and version, from
    the same input file (size and modification time), and its output file exists."""
    if not rec or rec.get("status") != "done" or not output.is_file():
        return False
    if (rec.get("task"), rec.get("options"), rec.get("version")) != (task, options, version):
        return False
    try:
        st = input.stat()
    except OSError:
        return False
    return (rec.get("input_size"), rec.get("input_mtime_ns")) == (st.st_size, st.st_mtime_ns)


def remove_stale_temporaries(outputs: list[Path]) -> int:
    """Delete the temporary files (``.NAME.*.tmp``) that atomic writes of these outputs left
    behind when their worker was killed mid-write; returns how many were removed."""
    n = 0
    for o in outputs:
        for t in o.parent.glob(f".{glob.escape(o.name[:_TMP_NAME_MAX])}.*.tmp"):
            try:
                t.unlink()
                n += 1
            except OSError:
                pass
    return n
