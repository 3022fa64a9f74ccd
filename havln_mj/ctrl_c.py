"""Ctrl-C that is remembered even where Python cannot raise it.

A SIGINT becomes a KeyboardInterrupt wherever the interpreter happens to be. Where that is a
callback Python cannot raise from (the import system's weakref callbacks), the interrupt is
lost and printed as a traceback; where it is a library that catches every exception (rtree's
loader), it is lost silently. :class:`CtrlC` remembers it in both cases, so a command can stop
at its next checkpoint, and keeps the lost one off the terminal.
"""

from __future__ import annotations

import signal
import sys
import threading


class CtrlC:
    """Remembers a Ctrl-C (SIGINT) while installed.

    Attributes:
        seen: Whether a Ctrl-C came while installed, raised or lost.
    """

    def __init__(self) -> None:
        self.seen = False
        self._previous_handler = None
        self._previous_hook = None

    def _handle(self, signum: int, frame: object) -> None:
        self.seen = True
        raise KeyboardInterrupt

    def _unraisable(self, unraisable: object) -> None:
        if issubclass(unraisable.exc_type, KeyboardInterrupt):
            self.seen = True
        else:
            (self._previous_hook or sys.__unraisablehook__)(unraisable)

    def install(self) -> None:
        """Takes over SIGINT and the unraisable hook, unless SIGINT is ignored or off-thread."""
        if threading.current_thread() is not threading.main_thread():
            return
        previous = signal.getsignal(signal.SIGINT)
        if previous is not signal.SIG_IGN:
            self._previous_handler = previous
            signal.signal(signal.SIGINT, self._handle)
            self._previous_hook, sys.unraisablehook = sys.unraisablehook, self._unraisable

    def restore(self) -> None:
        """Puts the earlier SIGINT handler and unraisable hook back."""
        if self._previous_handler is not None:
            signal.signal(signal.SIGINT, self._previous_handler)
            sys.unraisablehook = self._previous_hook
            self._previous_handler = self._previous_hook = None
