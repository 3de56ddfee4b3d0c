"""A job run in a forked worker process while this process runs another (:func:`side_by_side`).

Used to draw a run's figures in two halves at once (:func:`ccopt.plots.write_figures`) on a machine
whose second core would otherwise idle.
"""

from __future__ import annotations

import multiprocessing
import pickle
import signal
import sys
from collections.abc import Callable
from multiprocessing.connection import Connection
from pathlib import Path

from ccopt.stops import STOP_SIGNALS

FORK = sys.platform.startswith("linux")
"""Whether :func:`side_by_side` forks a worker: on Linux. Elsewhere a fork is missing (Windows) or
unsafe once the system's libraries are loaded (macOS), and a spawned worker would import everything
again (half a second), so the two jobs run one after the other."""


def side_by_side(here: Callable[[], list[Path]], there: Callable[[], list[Path]]) -> list[Path]:
    """``here() + there()``, with ``there`` run in a forked worker process while this one runs
    ``here`` (one after the other without :data:`FORK`).

    An exception either raises here, this process's own first. On any exception, ``KeyboardInterrupt``
    included, the worker is stopped before it propagates, so that no file is written after it: the
    caller may then remove what the two wrote. The worker ignores Ctrl-C (this process stops it) and
    dies quietly when stopped: the stop signals wait, blocked, until it has set its handlers.
    """
    if not FORK:
        return here() + there()
    context = multiprocessing.get_context("fork")
    receiving, sending = context.Pipe(duplex=False)
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)  # until the worker has its handlers
    worker = context.Process(target=_work, args=(there, sending, mask), daemon=True)
    try:
        worker.start()
    except BaseException:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        raise
    try:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        sending.close()
        mine = here()
        try:
            done, theirs = receiving.recv()
        except EOFError:
            worker.join()
            raise RuntimeError(f"the figure worker ended with exit code {worker.exitcode}") from None
    finally:
        if worker.is_alive():
            worker.terminate()
        worker.join()
        receiving.close()
    if not done:
        raise theirs
    return mine + theirs


def _work(job: Callable[[], list[Path]], sending: Connection, mask: set[signal.Signals]) -> None:
    """The worker of :func:`side_by_side`: send ``(True, job())`` or, if it raised, ``(False, the
    exception)`` (a ``RuntimeError`` with its type and message if it cannot be pickled). ``mask``:
    the signal mask to restore once its handlers are set."""
    for number in STOP_SIGNALS:
        signal.signal(number, signal.SIG_IGN if number == signal.SIGINT else signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    try:
        message = (True, job())
    except Exception as error:  # handed to the parent, which raises it
        message = (False, _picklable(error))
    sending.send(message)
    sending.close()


def _picklable(error: Exception) -> Exception:
    """``error`` if it survives pickling, else a ``RuntimeError`` naming its type and message."""
    try:
        pickle.loads(pickle.dumps(error))
    except Exception:  # any failure to pickle or to rebuild it
        return RuntimeError(f"{type(error).__name__}: {error}")
    return error
