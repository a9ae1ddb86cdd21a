"""Ctrl-C and SIGTERM during a run: finish the current chunk, keep what was written, stop cleanly."""
from __future__ import annotations

import signal
import threading

__all__ = ["SignalStop"]


class SignalStop:
    """While alive (main thread only), SIGINT/SIGTERM set ``signum`` instead of stopping the program;
    a second signal raises KeyboardInterrupt at once. ``restore()`` puts the earlier handlers back.

    The time loop polls ``signum`` between steps; the CLI also holds signals this way while it
    writes a run's outputs, so that they are complete."""

    def __init__(self, enabled):
        self.signum, self.old = None, {}
        if enabled and threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                if signal.getsignal(sig) is signal.SIG_IGN:     # e.g. SIGINT of a background job: keep ignoring
                    continue
                self.old[sig] = signal.signal(sig, self._handler)

    def _handler(self, signum, frame):
        if self.signum is not None:
            self.restore()
            raise KeyboardInterrupt(f"second {signal.Signals(signum).name}")
        self.signum = signum

    def restore(self):
        for sig, handler in self.old.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)
        self.old = {}
