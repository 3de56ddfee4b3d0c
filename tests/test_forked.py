"""A job in a forked worker beside this process's own (ccopt.forked.side_by_side): both run, errors
and deaths in the worker surface here, signals stop it quietly, and an error here stops it first."""

import multiprocessing
import os
import signal
from time import sleep

import pytest

from ccopt import forked


def _writes_pid(path):
    """A job that writes the id of the process that runs it into ``path``."""

    def job():
        path.write_text(str(os.getpid()))
        return [path]

    return job


@pytest.mark.parametrize("fork", [True, False])
def test_side_by_side_runs_the_second_job_in_a_forked_worker(tmp_path, monkeypatch, fork):
    monkeypatch.setattr(forked, "FORK", fork)
    paths = forked.side_by_side(_writes_pid(tmp_path / "here"), _writes_pid(tmp_path / "there"))
    assert paths == [tmp_path / "here", tmp_path / "there"]
    here, there = (int(path.read_text()) for path in paths)
    assert here == os.getpid() and (there != here) == fork
    assert not multiprocessing.active_children()


class _NeedsTwo(Exception):
    """An exception that pickles but cannot be rebuilt from its pickle (its ``__init__`` takes two)."""

    def __init__(self, what, why):
        super().__init__(f"{what}: {why}")


def _raises(error):
    def job():
        raise error

    return job


@pytest.mark.parametrize(
    ("error", "raised", "message"),
    [
        (OSError(28, "No space left on device"), OSError, "No space left on device"),
        (_NeedsTwo("frame 3", "bad"), RuntimeError, "_NeedsTwo: frame 3: bad"),
    ],
)
def test_an_error_in_the_worker_raises_here(tmp_path, error, raised, message):
    with pytest.raises(raised, match=message):
        forked.side_by_side(_writes_pid(tmp_path / "here"), _raises(error))
    assert not multiprocessing.active_children()


def test_a_worker_that_dies_is_an_error_with_its_exit_code(tmp_path):
    with pytest.raises(RuntimeError, match="exit code 3"):
        forked.side_by_side(_writes_pid(tmp_path / "here"), lambda: os._exit(3))


def test_the_worker_ignores_ctrl_c_and_ends_quietly_when_stopped(tmp_path, capfd):
    """Ctrl-C reaches every process of the terminal's group: the worker leaves it to this process,
    which stops it with SIGTERM (as SIGTERM or SIGHUP sent to the group do): no traceback."""

    def shrugs():
        os.kill(os.getpid(), signal.SIGINT)
        return _writes_pid(tmp_path / "there")()

    assert forked.side_by_side(list, shrugs) == [tmp_path / "there"]
    with pytest.raises(RuntimeError, match="exit code -15"):
        forked.side_by_side(list, lambda: os.kill(os.getpid(), signal.SIGTERM))
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("error", [ValueError("here first"), KeyboardInterrupt()])
def test_an_error_here_stops_the_worker_before_it_raises(tmp_path, error):
    """The caller may remove what was written once the error reaches it: the worker writes no more."""

    def slow():
        sleep(0.5)
        (tmp_path / "late").write_text("written after the error")
        return []

    with pytest.raises(type(error)):
        forked.side_by_side(_raises(error), slow)
    assert not multiprocessing.active_children() and not (tmp_path / "late").exists()
