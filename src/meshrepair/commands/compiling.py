"""Says when a command's time includes the one-off compilation of the numba kernels.

The kernels are compiled on their first use and kept in numba's on-disk cache, so the first run
of a command takes seconds longer than the next ones (a denoise of a 544-vertex mesh: 10.5 s
with an empty cache, 9.9 s of it compiling; 0.35 s with a full one). :class:`CompileClock`
listens to numba's ``numba:compile`` events, which fire only when a kernel is compiled (not when
it is loaded from the cache): at the first one it prints a one-line note (the wait that follows
is not the repair), and it adds up the seconds spent compiling, which the command's summary then
states.
"""

from __future__ import annotations

import sys
import time

NOTE_MIN_SECONDS = 0.5
"""Compilation shorter than this is not mentioned in the summary."""


class CompileClock:
    """Context manager timing the numba compilations of a command (no-op without numba)."""

    def __init__(self, announce: bool = True):
        self.announce = announce
        self.seconds = 0.0
        self.kernels = 0
        self.said = False  # the summary already stated the compile time
        self._depth = 0
        self._t0 = 0.0
        self._ctx = None

    def on_start(self, event) -> None:
        if self._depth == 0:
            if self.kernels == 0 and self.announce:
                print("compiling kernels (first run only; later runs load them from numba's "
                      "cache)", file=sys.stderr, flush=True)
            self.kernels += 1
            self._t0 = time.perf_counter()
        self._depth += 1

    def on_end(self, event) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._t0

    def __enter__(self) -> CompileClock:
        try:
            from numba.core import event as nb_event

            from meshrepair._kernels import HAVE_NUMBA
        except ImportError:
            return self
        if HAVE_NUMBA:
            clock = self

            class _Adapter(nb_event.Listener):  # numba accepts only its Listener subclasses
                def on_start(self, event):
                    clock.on_start(event)

                def on_end(self, event):
                    clock.on_end(event)

            self._ctx = nb_event.install_listener("numba:compile", _Adapter())
            self._ctx.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self._ctx is not None:
            self._ctx.__exit__(*exc)
            self._ctx = None

    def included(self) -> str:
        """``" including 9.8 s of one-off kernel compilation"`` for a summary's time (and marks
        it said), or ``""`` when compilation took less than :data:`NOTE_MIN_SECONDS`."""
        if self.seconds < NOTE_MIN_SECONDS:
            return ""
        self.said = True
        return f" including {self.seconds:.1f} s of one-off kernel compilation"

    def closing_note(self) -> str:
        """The line a command prints at its end when its summary did not state the compile time
        (``""`` if there is nothing to say)."""
        if self.said or self.seconds < NOTE_MIN_SECONDS:
            return ""
        return (f"note: this run included {self.seconds:.1f} s of one-off kernel compilation "
                "(first run only)")


CLOCK = CompileClock(announce=False)
"""The clock of the running command (the CLI replaces it at the start of each command)."""
