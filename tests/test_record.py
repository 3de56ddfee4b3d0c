"""The run record survives interruption and round-trips its data."""

import numpy as np
import pytest

from ccopt import record


def sample(k):
    return {"time": k * 0.01, "hand_pose": np.array([k, 2.0 * k, 0.1]), "mode": np.int8(k % 3 - 1)}


def test_round_trip(tmp_path):
    writer = record.RecordWriter(tmp_path / "run", {"seed": 3}, flush_every=7)
    for k in range(30):
        writer.append(sample(k))
    writer.close({"completed": True})
    loaded = record.load_record(tmp_path / "run")
    assert loaded.meta["status"] == "completed" and loaded.meta["seed"] == 3
    assert loaded.summary == {"completed": True}
    np.testing.assert_allclose(loaded["time"], np.arange(30) * 0.01)
    np.testing.assert_allclose(loaded["hand_pose"][:, 1], 2.0 * np.arange(30))
    assert not list((tmp_path / "run" / record.CHUNKS).glob("*.npz"))


def test_an_interrupted_run_keeps_its_flushed_chunks(tmp_path):
    writer = record.RecordWriter(tmp_path / "run", {}, flush_every=10)
    for k in range(25):
        writer.append(sample(k))
    # the process dies here: no close()
    loaded = record.load_record(tmp_path / "run")
    assert loaded.meta["status"] == "running"
    assert len(loaded["time"]) == 20


@pytest.mark.parametrize("moment", ["before the rename", "after the rename"])
def test_a_signal_while_a_chunk_is_written_loses_and_repeats_no_sample(tmp_path, monkeypatch, moment):
    """Ctrl-C or SIGTERM inside a flush: the run still closes with every sample once and no partial file."""
    save, replace = np.savez, record.os.replace
    interrupted = []

    def savez_once_cut_short(path, **arrays):
        save(path, **arrays)
        if moment == "before the rename" and not interrupted:
            interrupted.append(path)
            raise KeyboardInterrupt

    def replace_once_cut_short(source, target):
        replace(source, target)
        if moment == "after the rename" and not interrupted:
            interrupted.append(target)
            raise KeyboardInterrupt

    writer = record.RecordWriter(tmp_path / "run", {}, flush_every=10)
    monkeypatch.setattr(record.np, "savez", savez_once_cut_short)
    monkeypatch.setattr(record.os, "replace", replace_once_cut_short)
    with pytest.raises(KeyboardInterrupt):
        for k in range(25):
            writer.append(sample(k))
    writer.close(status="interrupted")
    assert interrupted
    loaded = record.load_record(tmp_path / "run")
    np.testing.assert_array_equal(loaded["time"], np.arange(10) * 0.01)
    assert not list((tmp_path / "run" / record.CHUNKS).iterdir())


def test_unwritable_folder_is_a_clear_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(ValueError, match="cannot write to output folder"):
        record.prepare_folder(blocker / "sub")
    with pytest.raises(ValueError, match="not a run folder"):
        record.load_record(tmp_path)


def test_changing_keys_is_refused(tmp_path):
    writer = record.RecordWriter(tmp_path / "run", {})
    writer.append(sample(0))
    with pytest.raises(ValueError, match="keys changed"):
        writer.append({"time": 1.0})


class _Interrupting:
    """A value whose conversion to an array is interrupted (as by Ctrl-C or SIGTERM mid-append)."""

    def __array__(self, dtype=None, copy=None):
        raise KeyboardInterrupt


def test_a_sample_interrupted_while_appended_is_dropped_whole(tmp_path):
    writer = record.RecordWriter(tmp_path / "run", {}, flush_every=3)
    for k in range(4):
        writer.append({"time": float(k), "x": np.full(2, k)})
    with pytest.raises(KeyboardInterrupt):
        writer.append({"time": 4.0, "x": _Interrupting()})
    writer.close(status="interrupted")
    data = record.load_record(tmp_path / "run").data
    np.testing.assert_array_equal(data["time"], [0.0, 1.0, 2.0, 3.0])
    assert data["x"].shape == (4, 2)
