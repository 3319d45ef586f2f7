"""Command-line parsing rules shared by every sub-command (argparse only, no work).

* :func:`normalise_argv` lets users write options anywhere and give negative numbers as values:
  ``--sphere -0.2,0.1,0.3,0.05`` (argparse would take ``-0.2,...`` for an option),
  ``fill --holes 1 2 IN OUT`` (a list option would swallow the positionals), ``-v``/``-q``
  before or after the command.
* :func:`document_defaults` appends ``(default: X)`` to every option's help that does not state
  its default yet, so ``--help`` shows every default.

Both work from the parser's own actions, so commands added later follow the same rules.
"""

from __future__ import annotations

import argparse
import re

# a value that starts with '-' but is a number or a list of numbers, e.g. -0.2 or -1,2.5e-3,4
_NUMBERISH = re.compile(r"^-(\d|\.\d)[\d.eE+\-,\s]*$")
_GLOBAL_ONLY = ("-v", "--verbose")
_QUIET = ("-q", "--quiet")


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for a in parser._actions:  # argparse keeps them here; there is no public accessor
        if isinstance(a, argparse._SubParsersAction):
            return dict(a.choices)
    return {}


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {s: a for a in parser._actions for s in a.option_strings}


def _takes_one_value(a: argparse.Action) -> bool:
    return a.nargs is None and not isinstance(
        a, (argparse._StoreConstAction, argparse._CountAction, argparse._HelpAction,
            argparse._VersionAction, argparse._AppendConstAction))


def _parses_as(a: argparse.Action, tok: str) -> bool:
    if a.type not in (int, float):
        return False
    try:
        a.type(tok)
    except ValueError:
        return False
    return True


def _is_verbose(tok: str) -> bool:
    return tok in _GLOBAL_ONLY or bool(re.fullmatch(r"-v+", tok))


def normalise_argv(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """Rewrite ``argv`` so that argparse reads it as the user meant (see the module docstring).

    Only these rewrites are made, and only after the sub-command is identified:

    1. ``--opt -0.2,...`` -> ``--opt=-0.2,...`` for options that take one value;
    2. a numeric list option (``nargs='+'`` with ``type=int``/``float``) keeps only the tokens
       that parse as its type and moves to the end, so positionals after it stay positionals;
    3. ``-v``/``--verbose`` (options of the main parser) move before the command; ``-q``/
       ``--quiet`` move after it when the command defines it, else before it;
    4. for a command with an optional positional (``denoise IN [OUT]``), the positionals move
       before the options, so that ``denoise a.ply --quiet b.ply`` still reads ``b.ply`` as OUT.

    Tokens after a ``--`` separator are left alone.
    """
    subs = _subparsers(parser)
    argv = list(argv)
    i_cmd = next((i for i, t in enumerate(argv) if t in subs), None)
    if i_cmd is None:
        return argv
    head, cmd, rest = argv[:i_cmd], argv[i_cmd], argv[i_cmd + 1:]
    sub = subs[cmd]
    opts = _options(sub)
    sub_quiet = any(q in opts for q in _QUIET)
    before, after, tail, positionals = [], [], [], []
    # argparse fills an optional positional (nargs="?") only from the positionals that stand
    # together: with one, they are gathered before the options
    optional_positional = any(not a.option_strings and a.nargs == "?" for a in sub._actions)
    for t in head:
        (after if t in _QUIET and sub_quiet else before).append(t)
    i = 0
    while i < len(rest):
        t = rest[i]
        if t == "--":
            after.extend(rest[i:])
            break
        a = opts.get(t)
        if a is None and t.startswith("--") and "=" not in t:  # argparse's unique prefixes
            hits = {id(b): b for o, b in opts.items() if o.startswith(t)}
            a = next(iter(hits.values())) if len(hits) == 1 else None
        if a is None:
            if _is_verbose(t) and t not in opts:
                before.append(t)
            elif t in _QUIET and not sub_quiet:
                before.append(t)
            elif optional_positional and not t.startswith("-"):
                positionals.append(t)
            else:
                after.append(t)
            i += 1
            continue
        if _takes_one_value(a):
            if i + 1 < len(rest) and _NUMBERISH.match(rest[i + 1]):
                after.append(f"{t}={rest[i + 1]}")
                i += 2
                continue
            after.append(t)
            if i + 1 < len(rest):
                after.append(rest[i + 1])
            i += 2
            continue
        if a.nargs in ("+", "*") and a.type in (int, float):
            j = i + 1
            while j < len(rest) and _parses_as(a, rest[j]):
                j += 1
            if j > i + 1:
                tail.extend(rest[i:j])
                i = j
                continue
        after.append(t)
        i += 1
    return [*before, cmd, *positionals, *after, *tail]


def document_defaults(parser: argparse.ArgumentParser) -> None:
    """Append ``(default: X)`` to the help of every option of every sub-command whose help does
    not mention its default (flags and options without a default are left as they are)."""
    for sub in [parser, *_subparsers(parser).values()]:
        for a in sub._actions:
            if a.help in (None, argparse.SUPPRESS) or "default" in a.help.lower():
                continue
            if isinstance(a, (argparse._StoreTrueAction, argparse._StoreFalseAction,
                              argparse._HelpAction, argparse._VersionAction,
                              argparse._SubParsersAction)):
                continue
            d = a.default
            if d is None or d is argparse.SUPPRESS or d is False or (
                    isinstance(a, argparse._CountAction) and d == 0):
                continue
            if isinstance(d, (list, tuple)):
                d = " ".join(str(x) for x in d)
            a.help = f"{a.help} (default: {str(d).replace('%', '%%')})"


def _close_options(sub: argparse.ArgumentParser, token: str) -> list[str]:
    """The options of ``sub`` closest to the unknown ``token``: difflib's ratio to the whole
    option or to one of its words (``--iterations`` is close to ``--feature-iters`` by its word
    ``iters``); the best, and any as close, if at least 0.6. A token of one or two letters
    (``-n``) is too short for a ratio (it is close to every short word): the options with a word
    starting with it, when there are at most three."""
    import difflib

    name = token.split("=", 1)[0].lstrip("-").lower()
    words = {o: [o[2:], *o[2:].split("-")] for o in _options(sub) if o.startswith("--")}
    if len(name) < 3:
        hits = [o for o, ws in words.items() if any(w.startswith(name) for w in ws)]
        return hits if 0 < len(hits) <= 3 else []
    best = {o: max(difflib.SequenceMatcher(None, name, w).ratio() for w in ws)
            for o, ws in words.items()}
    if not best:
        return []
    top = max(best.values())
    if top < 0.6:
        return []
    return [o for o, r in best.items() if r >= top - 0.02][:3]


_OUTPUT_FLAGS = frozenset({"o", "out", "output", "outfile", "output-file"})
"""Options other tools name their output with; here the output is a positional argument."""


def parse_or_explain(parser: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """``parser.parse_args(argv)``, except that arguments the sub-command does not know are
    reported with the sub-command's usage (not the top-level one) and, for each unknown option,
    the closest known one (``--iterations`` -> ``did you mean --iters?``), or, for an output
    option other tools have (``-o``, ``--output``), where the output goes. Exits with status 2,
    as argparse does."""
    import sys

    args, extra = parser.parse_known_args(argv)
    if not extra:
        return args
    cmd = getattr(args, "command", None)
    sub = _subparsers(parser).get(cmd) if cmd else None
    target = sub or parser
    hints = []
    positional = ({a.dest: (f"[{a.metavar or a.dest}]" if a.nargs == "?" else
                            str(a.metavar or a.dest))
                   for a in sub._actions if not a.option_strings} if sub is not None else {})
    for t in extra:
        name = t.split("=", 1)[0]
        if (t.startswith("-") and name.lstrip("-").lower() in _OUTPUT_FLAGS
                and "output" in positional):
            names = " ".join(v for k, v in positional.items() if k != "command")
            hints.append(f"{name}: the output file is given without an option, after the "
                         f"input: {sub.prog} {names}")
            continue
        if t.startswith("-") and sub is not None:
            close = _close_options(sub, t)
            if close:
                hints.append(f"{t.split('=', 1)[0]}: did you mean {' or '.join(close)}?")
    msg = "unrecognized arguments: " + " ".join(extra)
    if hints:
        msg += "\n" + "\n".join(hints)
    target.print_usage(sys.stderr)
    target.exit(2, f"{target.prog}: error: {msg}\n")
    raise AssertionError("unreachable")  # pragma: no cover
