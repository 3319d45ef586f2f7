"""CLI traps of issue 11: negative numbers as values, options anywhere, -v/-q anywhere, closed
pipes, no stray progress bar before an error, help with every default."""

from __future__ import annotations

import argparse
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from meshrepair.cli import build_parser, main
from meshrepair.commands.parsing import _subparsers, normalise_argv
from meshrepair.io import read_mesh, write_mesh


@pytest.fixture
def meshes(tmp_path):
    m = trimesh.creation.icosphere(3)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    c = V[F].mean(axis=1)
    keep = (c[:, 2] < 0.8) & (c[:, 0] < 0.8)  # two holes
    used = np.unique(F[keep])
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    sphere = write_mesh(tmp_path / "s.ply", V, F)
    holed = write_mesh(tmp_path / "h.ply", V[used], remap[F[keep]])
    return sphere, holed


def test_negative_numbers_as_option_values(tmp_path, meshes, capsys):
    s, _ = meshes
    out = tmp_path / "o.ply"
    # used to fail with "expected one argument" (needed --sphere=-0.2,...)
    assert main(["inpaint", str(s), str(out), "--sphere", "-0.2,0.1,0.97,0.2", "-q"]) == 0
    assert read_mesh(out).n_faces > 0
    args = build_parser().parse_args(normalise_argv(build_parser(), [
        "inpaint", "a.ply", "b.ply", "--box", "-1,-1,-1e-1,1,1,1"]))
    assert args.box == "-1,-1,-1e-1,1,1,1"
    args = build_parser().parse_args(normalise_argv(build_parser(), [
        "render", "a.ply", "b.png", "--azimuth", "-30", "--elevation", "-.5"]))
    assert (args.azimuth, args.elevation) == (-30.0, -0.5)


@pytest.mark.parametrize("opt", ["--holes", "--exclude"])
def test_list_options_before_the_positionals(tmp_path, meshes, capsys, opt):
    _, h = meshes
    out = tmp_path / "o.ply"
    # used to swallow IN and OUT ("the following arguments are required")
    assert main(["fill", opt, "0", str(h), str(out), "-q"]) == 0
    text = capsys.readouterr().out
    assert "1 filled, 1 skipped" in text
    p = build_parser()
    args = p.parse_args(normalise_argv(p, ["fill", "--holes", "1", "0", "a.ply", "b.ply"]))
    assert args.holes == [1, 0] and (args.input, args.output) == ("a.ply", "b.ply")
    args = p.parse_args(normalise_argv(p, ["fill", "a.ply", "--exclude", "2", "b.ply"]))
    assert args.exclude == [2] and args.output == "b.ply"


def test_verbose_and_quiet_before_or_after_the_command():
    p = build_parser()
    for argv in (["-v", "denoise", "a.ply", "b.ply", "-q"],
                 ["denoise", "a.ply", "b.ply", "-v", "-q"],
                 ["-q", "denoise", "-v", "a.ply", "b.ply"],
                 ["denoise", "--verbose", "a.ply", "--quiet", "b.ply"]):
        args = p.parse_args(normalise_argv(p, argv))
        assert args.verbose == 1 and args.quiet, argv
        assert (args.input, args.output) == ("a.ply", "b.ply")
    args = p.parse_args(normalise_argv(p, ["metrics", "a.ply", "b.ply", "-vv", "-q"]))
    assert args.verbose == 2  # -q is accepted by a command without a progress bar too
    # prefixes of long options still work, and values after -- are left alone
    args = p.parse_args(normalise_argv(p, ["fill", "--hol", "3", "a.ply", "b.ply"]))
    assert args.holes == [3]


def test_closed_pipe_is_quiet(meshes):
    s, _ = meshes
    proc = subprocess.Popen([sys.executable, "-m", "meshrepair.cli", "metrics", str(s), str(s)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # like `| head -0`: the reader is gone before anything is printed
    err = proc.stderr.read().decode()
    proc.wait(timeout=60)
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert proc.returncode == 141


def test_no_progress_bar_before_an_error(tmp_path, meshes, capsys):
    _, h = meshes
    assert main(["fill", str(h), str(tmp_path / "o.ply"), "--holes", "7"]) == 2
    err = capsys.readouterr().err
    assert "error" in err and "0it" not in err and "it/s" not in err, err


def test_every_option_has_help_with_its_default():
    p = build_parser()
    missing, no_default = [], []
    for name, sub in _subparsers(p).items():
        for a in sub._actions:
            if isinstance(a, argparse._HelpAction):
                continue
            where = f"{name} {'/'.join(a.option_strings) or a.dest}"
            if not a.help:
                missing.append(where)
            elif (a.default not in (None, False, argparse.SUPPRESS)
                  and "default" not in a.help.lower()):
                no_default.append(where)
    assert not missing, f"options without help: {missing}"
    assert not no_default, f"options whose help does not show the default: {no_default}"
    text = _subparsers(p)["denoise"].format_help()
    text = text[text.index("options:"):]
    for opt, default in (("--th", "30"), ("--tol", "1e-06"), ("--inner-solver", "armijo"),
                         ("--n-solver", "auto")):
        block = text[text.index(opt):]
        assert f"default: {default}" in block[:400], opt
    assert "result" in _subparsers(p)["metrics"].format_help()


@pytest.mark.parametrize(("cmd", "bad", "hint"), [
    ("denoise", "--iterations", "--robust-iters or --feature-iters"),
    ("fill", "--keepborder", "--keep-border"),
    ("denoise", "--lamda=3", "--lam"),
])
def test_unknown_option_shows_the_sub_command_usage_and_a_close_match(meshes, tmp_path, capsys,
                                                                     cmd, bad, hint):
    sphere, _ = meshes
    with pytest.raises(SystemExit) as exc:
        main([cmd, str(sphere), str(tmp_path / "o.ply"), bad, *(["3"] if "=" not in bad else [])])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"usage: meshrepair {cmd} ")  # the sub-command's usage, not the top's
    assert "COMMAND ..." not in err
    assert f"did you mean {hint}?" in err
    assert not (tmp_path / "o.ply").exists()


def test_unknown_option_far_from_every_option_gets_no_guess(meshes, tmp_path, capsys):
    sphere, _ = meshes
    with pytest.raises(SystemExit):
        main(["fill", str(sphere), str(tmp_path / "o.ply"), "--xyz"])
    err = capsys.readouterr().err
    assert "usage: meshrepair fill" in err and "unrecognized arguments: --xyz" in err
    assert "did you mean" not in err


@pytest.mark.parametrize(("cmd", "flag", "usage"), [
    ("denoise", "-o", "meshrepair denoise input [output]"),
    ("fill", "--output", "meshrepair fill input [output]"),
    ("render", "--out", "meshrepair render input output"),
])
def test_an_output_option_points_at_the_positional_output(meshes, tmp_path, capsys, cmd, flag,
                                                          usage):
    """Other tools name their output with -o / --output; here it is the second positional
    argument, and the message says so instead of guessing an unrelated option."""
    sphere, _ = meshes
    out = tmp_path / ("o.png" if cmd == "render" else "o.ply")
    with pytest.raises(SystemExit) as exc:
        main([cmd, str(sphere), flag, str(out)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"{flag}: the output file is given without an option, after the input: {usage}" in err
    assert "did you mean" not in err
    assert not out.exists()


@pytest.mark.parametrize(("cmd", "bad", "hint"), [
    ("denoise", "-n", "did you mean --n-solver?"),
    ("fill", "-n", "did you mean --no-refine?"),  # not --save-on-interrupt by its "on"
    ("denoise", "-x", None),
    ("denoise", "-s", None),  # save-mask, save-on-interrupt, inner-solver, n-solver: no one
])
def test_a_one_letter_unknown_option_is_matched_by_a_word_prefix(meshes, tmp_path, capsys, cmd,
                                                                 bad, hint):
    sphere, _ = meshes
    with pytest.raises(SystemExit):
        main([cmd, str(sphere), str(tmp_path / "o.ply"), bad])
    err = capsys.readouterr().err
    assert f"unrecognized arguments: {bad}" in err
    if hint is None:
        assert "did you mean" not in err
    else:
        assert f"{bad}: {hint}" in err


def test_a_stray_word_output_is_not_read_as_an_option(meshes, tmp_path, capsys):
    sphere, _ = meshes
    with pytest.raises(SystemExit):
        main(["denoise", str(sphere), str(tmp_path / "o.ply"), "output"])
    err = capsys.readouterr().err
    assert "unrecognized arguments: output" in err
    assert "given without an option" not in err
