"""Atomic file writes: the bytes go to a temporary file next to the target, which is renamed
over (or linked to) the target only once everything was written.

A failed or interrupted write therefore never leaves a truncated file and never destroys the
previous content of the target. Every writer of the project uses :func:`atomic_write` (meshes in
:func:`meshrepair.io.write_mesh`, PNG pictures, HTML reports, JSON logs); the command-line rule
for *which* paths may be written (never an input, never an existing file without ``--force``)
is :func:`meshrepair.commands.common.output_path`.

Example
-------
>>> with atomic_write("run.json", "w") as fh:      # doctest: +SKIP
...     fh.write(text)
"""

from __future__ import annotations

import json
import math
import os
import secrets
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from meshrepair.errors import MeshRepairError

__all__ = ["atomic_write", "check_writable", "write_json"]

_TMP_NAME_MAX = 64  # characters of the target name kept in the temporary name


def _os_message(exc: OSError) -> str:
    return exc.strerror or str(exc)


def check_writable(path: str | os.PathLike, *, overwrite: bool = True) -> Path:
    """Check that ``path`` can be (re)written: its folder exists and it is not a folder, FIFO,
    device or other non-regular file (those are refused even with ``overwrite``).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MeshRepairError
        If the folder is missing, the path is impossible (e.g. too long), it names an existing
        non-regular file, or it exists and ``overwrite`` is False.
    """
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        st = None
        if os.path.islink(p) and not overwrite:  # the name is taken by a link to nothing
            raise MeshRepairError(f"cannot write '{p}': it is a dangling symbolic link (to "
                                  f"'{os.readlink(p)}'); pass overwrite=True / --force to "
                                  "replace the link, or choose another name") from None
    except OSError as exc:  # name too long, not a directory, permission, loop, ...
        raise MeshRepairError(f"cannot write '{p}': {_os_message(exc)}") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise MeshRepairError(f"cannot write '{p}': it is a directory; give a file name")
        if not stat.S_ISREG(st.st_mode):
            raise MeshRepairError(f"cannot write '{p}': it exists and is not a regular file "
                                  "(FIFO, device or socket); choose another name")
        if not overwrite:
            raise MeshRepairError(f"cannot write '{p}': file exists (pass overwrite=True / "
                                  "--force to replace it)")
    parent = p.parent
    try:
        ok = parent.is_dir()
    except OSError as exc:
        raise MeshRepairError(f"cannot write '{p}': {_os_message(exc)}") from None
    if not ok:
        raise MeshRepairError(f"cannot write '{p}': directory '{parent}' does not exist")
    return p


@contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "wb", *, overwrite: bool = True,
                 encoding: str | None = None, make_parents: bool = False
                 ) -> Iterator[IO[Any]]:
    """Open a temporary file for writing; on a clean exit it atomically becomes ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The target file. Its folder must exist.
    mode : {"wb", "w"}
        Binary or text (text is UTF-8 unless ``encoding`` says otherwise).
    overwrite : bool
        If False, an existing ``path`` is never replaced, even one created while writing
        (the final step is a hard link, which fails if the target exists).
    encoding : str, optional
        Text encoding for ``mode="w"``.
    make_parents : bool
        Create missing parent folders first (else a missing folder is an error).

    Yields
    ------
    file object
        Write to it; do not close it.

    Raises
    ------
    MeshRepairError
        See :func:`check_writable`; also for any OS error while writing (disk full, ...). The
        target is left as it was and the temporary file is removed, also when the body raises.
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"atomic_write mode must be 'wb' or 'w', got {mode!r}")
    if make_parents:
        try:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise MeshRepairError(f"cannot write '{path}': {_os_message(exc)}") from None
    p = check_writable(path, overwrite=overwrite)
    tmp = p.parent / f".{p.name[:_TMP_NAME_MAX]}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0),
                     0o666)
    except OSError as exc:
        raise MeshRepairError(f"cannot write '{p}': {_os_message(exc)}") from None
    try:
        kw = {} if mode == "wb" else {"encoding": encoding or "utf-8", "newline": ""}
        with os.fdopen(fd, mode, **kw) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        _commit(tmp, p, overwrite)
    except OSError as exc:
        raise MeshRepairError(f"cannot write '{p}': {_os_message(exc)}") from None
    finally:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass


def _commit(tmp: Path, p: Path, overwrite: bool) -> None:
    if overwrite:
        os.replace(tmp, p)
        return
    try:
        os.link(tmp, p)  # fails if p exists: no race between the check and the write
    except FileExistsError:
        raise MeshRepairError(f"cannot write '{p}': file exists (it appeared while writing; "
                              "pass overwrite=True / --force to replace it)") from None
    except OSError:  # file system without hard links
        if os.path.lexists(p):
            raise MeshRepairError(f"cannot write '{p}': file exists") from None
        os.replace(tmp, p)


def write_json(path: str | os.PathLike, data: Any, *, overwrite: bool = True) -> Path:
    """Write ``data`` as indented JSON with :func:`atomic_write`; ``path`` must end with
    ``.json``. Numpy arrays and scalars are converted; other unknown objects become a float if
    they can, else their ``str``.

    Returns
    -------
    pathlib.Path
    """
    p = Path(path)
    if p.suffix.lower() != ".json":
        raise MeshRepairError(f"cannot write '{p}': a JSON log must have a .json name")
    text = json_text(data, indent=1)
    with atomic_write(p, "w", overwrite=overwrite) as fh:
        fh.write(text)
    return p


def json_text(data: Any, **kw) -> str:
    """``data`` as strict JSON text (``json.dumps`` keywords ``kw``): numpy arrays and scalars
    converted, NaN and infinities written as null (strict parsers, jq and JavaScript refuse
    them)."""
    plain = _finite(json.loads(json.dumps(data, default=_jsonable)))
    return json.dumps(plain, allow_nan=False, **kw)


def _finite(x: Any) -> Any:
    """``x`` (parsed JSON) with every non-finite float replaced by None."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def _jsonable(x: Any) -> Any:
    try:
        import numpy as np

        if isinstance(x, np.ndarray):
            return x.tolist()
        if isinstance(x, np.generic):
            return x.item()
    except ImportError:  # pragma: no cover
        pass
    try:
        return float(x)
    except (TypeError, ValueError):
        return str(x)
