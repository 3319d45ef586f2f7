"""``import meshrepair`` is lazy (PEP 562): the public API is unchanged, and the package and the
command line's parser load neither numba nor scipy until a task runs."""

import importlib
import subprocess
import sys
import types

import pytest

import meshrepair


@pytest.mark.parametrize("name", meshrepair.__all__)
def test_every_public_name_imports(name):
    ns: dict = {}
    exec(f"from meshrepair import {name}", ns)
    obj = ns[name]
    assert obj is getattr(meshrepair, name)
    assert not isinstance(obj, types.ModuleType)  # denoise/complete: the functions, not modules
    home = importlib.import_module(obj.__module__)
    assert getattr(home, name) is obj
    assert name in dir(meshrepair)


def test_star_import_and_unknown_name():
    ns: dict = {}
    exec("from meshrepair import *", ns)
    assert set(meshrepair.__all__) <= set(ns)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        meshrepair.nope  # noqa: B018


def _run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip()


def test_package_and_cli_parser_do_not_load_numba_or_scipy():
    out = _run("import sys, meshrepair, meshrepair.cli as c; c.build_parser(); "
               "print(sorted(m for m in ('numba', 'scipy', 'trimesh') if m in sys.modules))")
    assert out == "[]"


def test_submodule_import_first_keeps_the_functions():
    """``meshrepair.denoise`` / ``meshrepair.complete`` stay the public functions even when
    their modules were imported first (as the eager imports had it)."""
    out = _run("import meshrepair.denoise.api, meshrepair.complete as c, sys; "
               "import meshrepair as m; print(callable(m.denoise) and m.denoise is "
               "sys.modules['meshrepair.denoise.api'].denoise, callable(m.complete), "
               "callable(c))")
    assert out == "True True True"
