"""How a run or a study stops: the stop signals (Ctrl-C, SIGTERM, SIGHUP), a stop that long work polls,
and set-up that a stop must not interrupt. The library's closed loop and the command-line programs
share it."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator

INTERRUPTED = 130
"""Exit status of a program stopped by Ctrl-C or a stop signal (128 + SIGINT)."""
STOP_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
"""The signals that stop a run or a study as Ctrl-C does (:func:`stop_signals`)."""


_stopping = threading.Event()
"""Set by the first stop signal: the program is on its way out (:func:`stop_requested`)."""
_held = threading.Event()
"""Set by a stop signal that came within :func:`stops_held`: it is raised when the block ends."""
_holding = [0]
"""How deep the main thread is in :func:`stops_held` blocks."""


@contextlib.contextmanager
def stop_signals(prog: str) -> Iterator[None]:
    """Within: SIGTERM and SIGHUP stop the program as Ctrl-C does, by ``KeyboardInterrupt`` in the main
    thread (a run then closes its record). Once one of the three has come, the next one ends the
    program at once and quietly: ``prog: ...`` on one line and exit status :data:`INTERRUPTED`, no
    traceback; so that this holds to the end, the handlers are then left in place. It ends the
    process outright (``os._exit``, after flushing stdout and stderr): an exception raised from the
    handler could be lost, as when CasADi runs the handlers from its C++ code and raises its own
    ``KeyboardInterrupt`` in place of theirs.

    Outside the main thread (where handlers cannot be set) it changes nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handle(signum: int, frame: object) -> None:
        if _stopping.is_set():
            sys.stderr.write(f"{prog}: {signal.Signals(signum).name} again: stopping now\n")
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(OSError, ValueError):  # a closed pipe, a closed stream
                    stream.flush()
            os._exit(INTERRUPTED)
        _stopping.set()
        interrupt()

    previous = {number: signal.signal(number, handle) for number in STOP_SIGNALS}
    try:
        yield
    finally:
        if not _stopping.is_set():
            for number, handler in previous.items():
                signal.signal(number, handler)


def stop_requested() -> bool:
    """Whether a stop signal has come under :func:`stop_signals` (or :func:`request_stop` was called):
    the program is on its way out. Long work polls it, because the ``KeyboardInterrupt`` a handler
    raises can be lost: CasADi, building a function (symbolic operations, ``casadi.Function``), runs
    the handlers from its C++ code and at times drops what they raise (2 times in 20 interrupts of a
    loop building functions; a Panda run stopped while its oracle built its LP exited 0, 2 times in
    40)."""
    return _stopping.is_set()


def request_stop() -> None:
    """Mark the program as on its way out (:func:`stop_requested`): for a stop signal handler of its
    own (a study's pool worker)."""
    _stopping.set()


def interrupt(*_: object) -> None:
    """What a stop signal's handler does once it has decided to stop: raise ``KeyboardInterrupt``,
    or hold it until the :func:`stops_held` block ends (unless one is held already: the user
    insists). Every handler goes through it, so that held set-up holds whatever stops it."""
    if _holding[0] and not _held.is_set():
        _held.set()
        return
    raise KeyboardInterrupt


@contextlib.contextmanager
def stops_held() -> Iterator[None]:
    """Within: a stop signal does not interrupt the block; it is raised as ``KeyboardInterrupt`` when
    the block ends (over an exception the block raised: the user asked to stop). For set-up that an
    interrupt would not stop but corrupt: a C extension's module initialisation turns it into
    ``ImportError: initialization failed``, CasADi building a function may drop it
    (:func:`stop_requested`), and once a Panda run stopped while it started was killed by SIGINT
    after it had handled the interrupt (4 of 40 such runs went wrong before its set-up was held and
    the loop polled, 0 of 80 after; 1 in a later CI run, stopped after its folder was made and
    before its loop's set-up: the progress bar's import, the check of its schedule, held since).
    That death has a cause in CPython (3.10–3.13 seen): an interrupt raised within code that
    ``exec`` or ``eval`` runs from a string (a named tuple or a data class being made, as a module
    is imported) is marked unhandled even when it is caught, and ``python -m`` then ends by SIGINT
    instead of its exit status, unless a later such ``eval`` clears the mark.

    Under :func:`stop_signals` it holds all three stop signals (a second one still ends the program
    at once); otherwise Ctrl-C, as long as no other handler than Python's own is set (a second
    Ctrl-C then interrupts at once).

    Outside the main thread (where signals are not handled) it changes nothing. Blocks nest: the
    outermost one raises.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    own = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    previous = signal.signal(signal.SIGINT, interrupt) if own else None
    _holding[0] += 1
    try:
        yield
    finally:
        _holding[0] -= 1
        if own:
            signal.signal(signal.SIGINT, previous)
        if not _holding[0] and _held.is_set():
            _held.clear()
            raise KeyboardInterrupt
