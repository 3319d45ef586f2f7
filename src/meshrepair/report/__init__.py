"""The HTML report of one run: the page (``page.write_report``), its HTML fragments
(``fragments``) and the solver-history plot (``convergence_plot``).

May import ``meshrepair.render``, ``meshrepair.viewer``, ``meshrepair.mesh``, ``meshrepair.io``
and the base modules; it imports no task.
"""
