"""The completion task: ``meshrepair.complete(V, F, faces, template)`` (in ``api``) grafts a
template patch (or the
mesh's own mirror image) onto a region and blends it: inputs (``inputs``), loop
resampling and cyclic correspondence (``correspondence``, ``loopmatch``), rigid alignment and ICP
(``rigid``, ``icp``, ``alignment``), stitching (``stitch``), seam blending (``blend``), symmetry
(``symmetry``), the option choices (``modes``) and the result (``result``).

May import: ``meshrepair.model``, ``meshrepair.mesh``, ``meshrepair.io``, ``meshrepair.holes``
and the base modules; never another task's insides.
"""
