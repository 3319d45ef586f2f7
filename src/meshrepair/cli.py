"""The ``meshrepair`` command: argument parsing only; every command calls the public API."""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys

from meshrepair import __version__
from meshrepair.errors import MeshRepairError

# sub-command modules in src/meshrepair/commands/, each with register(subparsers)
COMMANDS = ("denoise", "fill", "complete", "render", "report", "view", "batch")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="meshrepair",
        description="Repair triangle meshes with one variational model: feature-aware denoising, "
                    "hole filling and context-aware completion (Huska, Morigi, Recupero, "
                    "JMIV 2023). Start with 'meshrepair demo'.")
    p.add_argument("--version", action="version", version=f"meshrepair {__version__}")
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="log progress (-v) or debug details (-vv); before or after the command")
    p.add_argument("-q", "--quiet", action="store_true", dest="quiet_all",
                   help="no progress bars (also accepted after the command)")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            mod = importlib.import_module(f".commands.{name}", __package__)
        except ModuleNotFoundError as exc:
            if exc.name and exc.name.endswith(f"commands.{name}"):
                continue
            raise
        mod.register(sub)
    from meshrepair.commands.parsing import document_defaults

    document_defaults(p)
    return p


def main(argv: list[str] | None = None) -> int:
    from meshrepair.commands.parsing import normalise_argv, parse_or_explain

    parser = build_parser()
    args = parse_or_explain(parser, normalise_argv(parser, sys.argv[1:] if argv is None
                                                   else argv))
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    from threadpoolctl import threadpool_limits

    onces = [(h, _OncePerCommand()) for h in logging.getLogger().handlers]  # one per handler:
    for h, once in onces:  # each handler shows each warning once
        h.addFilter(once)
    try:
        from meshrepair.commands import compiling

        quiet = bool(getattr(args, "quiet", False) or getattr(args, "quiet_all", False))
        compiling.CLOCK = compiling.CompileClock(announce=not quiet)
        with threadpool_limits(1), compiling.CLOCK:  # BLAS threads only slow this work down
            rc = int(args.func(args) or 0)
        note = compiling.CLOCK.closing_note()
        if note:
            print(note)
        sys.stdout.flush()  # a closed pipe (| head) shows up here, not at exit
        return rc
    except BrokenPipeError:  # the reader went away (| head): stop quietly, like other tools
        try:  # and keep the interpreter's final flush from printing a second traceback
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError):  # stdout without a file descriptor (tests)
            pass
        return 141
    except MeshRepairError as exc:
        print(f"meshrepair: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("meshrepair: interrupted", file=sys.stderr)
        return 130
    finally:
        for h, once in onces:
            h.removeFilter(once)


class _OncePerCommand(logging.Filter):
    """Lets each warning through once per command: a command reads or checks the same mesh
    more than once (the solve, the report's renders, the viewer), and the same message about
    it (pinched vertices, unreferenced vertices) is news only the first time."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: set[tuple[str, int, str]] = set()

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        key = (record.name, record.levelno, record.getMessage())
        if key in self.seen:
            return False
        self.seen.add(key)
        return True


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
