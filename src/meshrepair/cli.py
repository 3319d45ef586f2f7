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
    from meshrepair.commands.parsing import normalise_argv

    parser = build_parser()
    args = parser.parse_args(normalise_argv(parser, sys.argv[1:] if argv is None else argv))
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    from threadpoolctl import threadpool_limits

    try:
        with threadpool_limits(1):  # sparse/BLAS threads only slow this workload down
            rc = int(args.func(args) or 0)
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
