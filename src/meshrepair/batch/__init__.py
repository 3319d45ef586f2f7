"""Repairing a collection: one mesh file through one task (``jobs``), input discovery, records
and resume (``collection``), the Dask orchestration on a laptop or a cluster (``orchestrate``)
and the collection's ``index.html`` (``report``).

May import every task, ``meshrepair.render``, ``meshrepair.report``, ``meshrepair.io`` and the
base modules; only ``meshrepair.commands`` and ``meshrepair.cli`` import it.
"""
