"""Inlined numba helpers copied across ``_kernels`` files stay identical.

numba's on-disk cache does not notice a change of an inlined helper defined in another file, so a
kernel file keeps its own copy of the helpers its kernels inline (``_kernels/faces.py``). This
reads the sources (numba or not) and checks that the copies did not drift apart.
"""

import ast
from pathlib import Path

import pytest

import meshrepair._kernels as K

HERE = Path(K.__file__).parent
COPIES = [("_tri", "faces.py", "venergy.py")]


def _function(path: Path, name: str) -> str:
    tree = ast.parse(path.read_text())
    found = [ast.dump(n) for n in ast.walk(tree)
             if isinstance(n, ast.FunctionDef) and n.name == name]
    assert len(found) == 1, f"{path.name}: {len(found)} definitions of {name}"
    return found[0]


@pytest.mark.parametrize(("name", "a", "b"), COPIES)
def test_inlined_helper_copies_are_identical(name, a, b):
    assert _function(HERE / a, name) == _function(HERE / b, name)
