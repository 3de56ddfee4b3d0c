"""Run folders are never mixed: reused, killed, stale, truncated and foreign-file folders."""

import json
import shutil

import numpy as np
import pytest

from ccopt import record


def sample(k, run=0.0):
    """Sample ``k`` of a run tagged ``run``: every value says which run and which sample it is."""
    return {"time": k * 0.01, "hand_pose": np.array([k, run, 0.1]), "mode": np.int8(k % 3 - 1)}


def killed_run(folder, count, run, flush_every=10, overwrite=False):
    """Write ``count`` samples and die without closing: only full chunks reach the disk."""
    writer = record.RecordWriter(folder, {"run": run}, flush_every=flush_every, overwrite=overwrite)
    for k in range(count):
        writer.append(sample(k, run))
    return writer


def finished_run(folder, count, run, overwrite=False):
    writer = killed_run(folder, count, run, overwrite=overwrite)
    writer.close({"run": run})
    return writer


def listing(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def assert_one_line(error, *names):
    message = str(error.value)
    assert "\n" not in message
    assert error.value.__context__ is None or error.value.__suppress_context__  # no chained traceback
    for name in names:
        assert name in message


def test_a_used_folder_is_refused_and_left_as_it_was(tmp_path):
    folder = tmp_path / "run"
    killed_run(folder, 25, run=1.0)
    before = listing(folder)
    with pytest.raises(ValueError, match="is not empty") as error:
        record.RecordWriter(folder, {})
    assert_one_line(error, str(folder))
    assert listing(folder) == before
    assert len(record.load_record(folder)["time"]) == 20


def test_overwriting_a_killed_run_keeps_only_the_new_run(tmp_path):
    folder = tmp_path / "run"
    killed_run(folder, 35, run=1.0)
    finished_run(folder, 7, run=2.0, overwrite=True)
    loaded = record.load_record(folder)
    assert loaded.meta["run"] == 2.0 and loaded.meta["status"] == "completed"
    np.testing.assert_array_equal(loaded["hand_pose"][:, 1], np.full(7, 2.0))
    np.testing.assert_allclose(loaded["time"], np.arange(7) * 0.01)


def test_overwrite_clears_every_file_a_run_writes(tmp_path):
    folder = tmp_path / "run"
    finished_run(folder, 12, run=1.0)
    for name in ("estimation.png", "animation.gif", "meta.partial", "record.partial.npz", ".write_probe"):
        (folder / name).write_text("left over")
    (folder / record.CHUNKS / "chunk_00009.partial.npz").write_text("half a chunk")
    killed_run(folder, 5, run=2.0, flush_every=2, overwrite=True)
    assert listing(folder) == ["chunks", "chunks/chunk_00001.npz", "chunks/chunk_00002.npz", "meta.json"]
    np.testing.assert_array_equal(record.load_record(folder)["hand_pose"][:, 1], np.full(4, 2.0))


@pytest.mark.parametrize(
    ("foreign", "named"),
    [
        ("notes.txt", "run/notes.txt"),
        ("figures/a.png", "run/figures"),
        ("chunks/readme.md", "chunks/readme.md"),
        ("chunks/old/x", "chunks/old"),
        ("photo.png", "run/photo.png"),
        ("talk.gif", "run/talk.gif"),
        ("draft.partial", "run/draft.partial"),
    ],
)
def test_overwrite_refuses_files_a_run_does_not_write(tmp_path, foreign, named):
    folder = tmp_path / "run"
    finished_run(folder, 12, run=1.0)
    (folder / foreign).parent.mkdir(parents=True, exist_ok=True)
    (folder / foreign).write_text("mine")
    before = listing(folder)
    with pytest.raises(ValueError, match="was not written by a run") as error:
        record.prepare_folder(folder, overwrite=True)
    assert_one_line(error, named)
    assert listing(folder) == before


@pytest.mark.parametrize("value", ["", ".", "./", "sub/.."])
def test_the_current_directory_is_refused(tmp_path, monkeypatch, value):
    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="is the current directory") as error:
        record.prepare_folder(value)
    assert_one_line(error, repr(value))
    assert listing(tmp_path) == ["sub"]


def test_a_file_or_a_path_under_a_file_is_refused_and_nothing_is_created(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(ValueError, match="exists and is not a folder") as error:
        record.prepare_folder(blocker, overwrite=True)
    assert_one_line(error, str(blocker))
    with pytest.raises(ValueError, match="cannot write to output folder"):
        record.prepare_folder(blocker / "run")
    with pytest.raises(ValueError, match="cannot write to output folder"):
        record.prepare_folder(tmp_path / "new" / "deeper" / ("x" * 300))  # parents created, then fails
    assert listing(tmp_path) == ["file"]


def test_a_stale_record_and_foreign_chunks_are_not_read(tmp_path):
    """A killed run in a folder that also holds another run's ``record.npz`` and chunks (as when two
    runs shared a folder before folders were checked) reads only its own samples."""
    finished_run(tmp_path / "old", 30, run=1.0)
    killed_run(tmp_path / "older", 30, run=3.0)
    killed_run(tmp_path / "run", 25, run=2.0)
    shutil.copy(tmp_path / "old" / "record.npz", tmp_path / "run" / "record.npz")
    for k, chunk in enumerate(sorted((tmp_path / "older" / record.CHUNKS).glob("*.npz"))):
        shutil.copy(chunk, tmp_path / "run" / record.CHUNKS / f"chunk_{k + 3:05d}.npz")
    loaded = record.load_record(tmp_path / "run")
    np.testing.assert_array_equal(loaded["hand_pose"][:, 1], np.full(20, 2.0))
    np.testing.assert_allclose(loaded["time"], np.arange(20) * 0.01)


def test_partial_chunks_are_never_read(tmp_path):
    folder = tmp_path / "run"
    writer = killed_run(folder, 25, run=2.0)
    chunks = folder / record.CHUNKS
    shutil.copy(chunks / "chunk_00002.npz", chunks / "chunk_00003.partial.npz")  # complete but not renamed
    (chunks / "chunk_00004.partial.npz").write_bytes(b"PK\x03\x04 half written")
    assert len(record.load_record(folder)["time"]) == 20
    writer.close()
    np.testing.assert_allclose(record.load_record(folder)["time"], np.arange(25) * 0.01)


def test_record_written_but_status_not_yet_updated_is_read(tmp_path):
    """Killed between writing ``record.npz`` (chunks removed) and updating ``meta.json``."""
    folder = tmp_path / "run"
    finished_run(folder, 25, run=2.0)
    meta = json.loads((folder / "meta.json").read_text())
    (folder / "meta.json").write_text(json.dumps({**meta, "status": "running"}))
    np.testing.assert_allclose(record.load_record(folder)["time"], np.arange(25) * 0.01)


def test_every_run_has_its_own_id(tmp_path):
    ids = [finished_run(tmp_path / str(k), 3, run=k).run_id for k in range(2)]
    assert ids[0] != ids[1] and all(len(i) == 32 and int(i, 16) >= 0 for i in ids)
    assert record.load_record(tmp_path / "0").meta["run_id"] == ids[0]


def truncate(path, keep=0.5):
    content = path.read_bytes()
    path.write_bytes(content[: int(len(content) * keep)])


def scramble(path):
    """Zero the middle third of the file: the zip directory at its end stays readable."""
    content = bytearray(path.read_bytes())
    third = len(content) // 3
    content[third : 2 * third] = bytes(third)
    path.write_bytes(bytes(content))


@pytest.mark.parametrize(
    "damage", [lambda p: truncate(p, 0.0), lambda p: truncate(p, 0.3), lambda p: truncate(p, 0.9), scramble]
)
def test_a_truncated_record_is_one_line_naming_it(tmp_path, damage):
    folder = tmp_path / "run"
    finished_run(folder, 300, run=2.0)
    damage(folder / "record.npz")
    with pytest.raises(ValueError, match="truncated or not a record file") as error:
        record.load_record(folder)
    assert_one_line(error, "record.npz")


def test_a_truncated_chunk_is_one_line_naming_it(tmp_path):
    folder = tmp_path / "run"
    killed_run(folder, 25, run=2.0)
    truncate(folder / record.CHUNKS / "chunk_00002.npz")
    with pytest.raises(ValueError, match="truncated or not a record file") as error:
        record.load_record(folder)
    assert_one_line(error, "chunk_00002.npz")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("[1, 2]", "is not a JSON object"),
        ('"running"', "is not a JSON object"),
        ('{"status": "runn', "is not readable JSON"),
        ("\udcff", "is not readable JSON"),
        ("[" * 100_000, "is not readable JSON"),
    ],
)
def test_a_malformed_meta_is_one_line_naming_it(tmp_path, content, message):
    folder = tmp_path / "run"
    finished_run(folder, 5, run=2.0)
    (folder / "meta.json").write_bytes(content.encode("utf-8", "surrogateescape"))
    with pytest.raises(ValueError, match=message) as error:
        record.load_record(folder)
    assert_one_line(error, "meta.json")


def test_a_malformed_summary_is_one_line_naming_it(tmp_path):
    folder = tmp_path / "run"
    finished_run(folder, 5, run=2.0)
    (folder / "summary.json").write_text("[]")
    with pytest.raises(ValueError, match="is not a JSON object") as error:
        record.load_record(folder)
    assert_one_line(error, "summary.json")


def test_a_folder_recorded_before_run_ids_still_loads(tmp_path):
    """The layout of earlier versions: no ``run_id`` in ``meta.json``, ``record.npz`` or the chunks."""
    old = tmp_path / "old"
    (old / record.CHUNKS).mkdir(parents=True)
    (old / "meta.json").write_text(json.dumps({"status": "completed", "seed": 4}))
    np.savez(old / "record.npz", time=np.arange(3.0), mode=np.zeros(3, np.int8))
    loaded = record.load_record(old)
    assert loaded.meta["seed"] == 4 and loaded.summary is None
    np.testing.assert_array_equal(loaded["time"], [0.0, 1.0, 2.0])
    (old / "record.npz").unlink()
    np.savez(old / record.CHUNKS / "chunk_00001.npz", time=np.arange(2.0), mode=np.zeros(2, np.int8))
    np.testing.assert_array_equal(record.load_record(old)["time"], [0.0, 1.0])


def test_the_run_id_key_is_reserved(tmp_path):
    writer = record.RecordWriter(tmp_path / "run", {})
    with pytest.raises(ValueError, match="reserved"):
        writer.append({record.RUN_ID_KEY: 1.0})
    with pytest.raises(ValueError, match="flush_every"):
        record.RecordWriter(tmp_path / "other", {}, flush_every=0)


def test_every_file_a_run_or_its_figures_write_is_a_run_file():
    """The names come from the modules that write them (the figures, the GIF, the feasibility maps
    and their temporary files), so a new figure cannot be left out of ``--overwrite`` unnoticed."""
    from ccopt import feasibility_map, plots

    written = {*plots.FIGURES, "animation.gif", feasibility_map.FIGURE_NAME, feasibility_map.FILE_NAME}
    written |= {f"{feasibility_map.FILE_NAME}.partial", "meta.partial", "summary.partial"}
    assert written <= record.RUN_FILES
