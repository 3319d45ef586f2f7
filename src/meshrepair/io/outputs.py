"""The one output rule of every command and batch job: an output is never an input, never
another output of the same command, never an existing file without ``force``; the file itself
is then written atomically (:func:`meshrepair.atomic.atomic_write`)."""

from __future__ import annotations

import os
from pathlib import Path

from meshrepair.atomic import check_writable
from meshrepair.errors import MeshRepairError

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
    o = Path(out)
    if suffixes is MESH_SUFFIXES:
        from meshrepair.io import SUPPORTED_FORMATS

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
