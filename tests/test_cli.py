"""The CLI: bad input gets one clear line and exit status 2, never a traceback."""

import subprocess
import sys

import pytest


def ccopt(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "ccopt.cli", *args], capture_output=True, text=True, cwd=cwd, timeout=120
    )


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["run", "--object", "dodecahedron"], "dodecahedron"),
        (["run", "--vertices", "0,0;100,0;50,10;50,100"], "convex"),
        (["run", "--vertices", "0,0;abc"], "--vertices"),
        (["run", "--mu-hand", "-0.5"], "-0.5"),
        (["run", "--mu-ground", "nan"], "nan"),
        (["run", "--mass", "-1"], "-1"),
        (["run", "--schedule", "zigzag"], "zigzag"),
        (["run", "--controller-hz", "5000"], "5000"),
        (["run", "--plant", "robot"], "robot"),
        (["plot", "/no/such/run"], "/no/such/run"),
        (["bench", "warp_speed"], "warp_speed"),
        (["study", "astrology"], "astrology"),
        (["frobnicate"], "frobnicate"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, named):
    result = ccopt(*args, "--no-progress") if args[0] == "run" else ccopt(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], result.stderr
    assert "Traceback" not in result.stderr


def test_malformed_schedule_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("steps: [{motion: pivot}]")
    result = ccopt("run", "--schedule", str(bad), "--no-progress")
    assert result.returncode == 2 and "delta_deg" in result.stderr and len(result.stderr.splitlines()) == 1


def test_unwritable_out(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = ccopt("run", "--out", str(blocker / "run"), "--no-progress")
    assert result.returncode == 2 and "cannot write to output folder" in result.stderr
    assert len(result.stderr.splitlines()) == 1


def test_help_everywhere():
    for args in (["--help"], ["run", "--help"], ["plot", "--help"], ["study", "--help"], ["bench", "--help"]):
        result = ccopt(*args)
        assert result.returncode == 0 and "usage" in result.stdout


def test_bare_ccopt_prints_its_usage_with_every_command():
    result = ccopt()
    assert result.returncode == 0 and result.stdout.startswith("usage: ccopt")
    for command in ("run", "plot", "view", "objects", "study", "bench"):
        assert f"\n    {command} " in result.stdout, command


def test_objects_lists_every_library_object_with_its_faces_and_mass():
    from ccopt import objects

    result = ccopt("objects")
    assert result.returncode == 0
    rows = {line.split()[0]: line.split() for line in result.stdout.splitlines()[2:] if line.strip()}
    for name in objects.OBJECT_NAMES:
        obj = objects.make_object(name)
        assert rows[name][1] == str(obj.n_faces), name
        assert f"{obj.mass:.3f}" in rows[name], name


def test_study_and_bench_without_a_name_list_each_script_on_one_line():
    from ccopt.cliutil import scripts

    for command, package in (("study", "studies"), ("bench", "benchmarks")):
        result = ccopt(command)
        assert result.returncode == 0
        found = scripts(package)
        listed = [line.split()[0] for line in result.stdout.splitlines()[1:-1]]
        assert listed == list(found) and len(found) >= 3, result.stdout


def test_a_study_names_itself_as_ccopt_study_in_its_errors_and_every_study_has_quick():
    from ccopt.cliutil import scripts

    bad = ccopt("study", "gradients", "--points", "0")
    assert bad.returncode == 2 and bad.stderr.startswith("ccopt study gradients: error:"), bad.stderr
    for name in scripts("studies"):
        result = ccopt("study", name, "--help")
        assert result.returncode == 0 and "--quick" in result.stdout, name
        assert result.stdout.startswith(f"usage: ccopt study {name}"), name


def test_plot_a_figure_the_worker_cannot_finish_is_one_line_and_leaves_none(tmp_path, capsys, monkeypatch):
    """The GIF is drawn in a second process (ccopt.forked.side_by_side): its failure, after writing
    part of the file, is the same one line, and neither its part nor the still figures drawn
    meanwhile are left."""
    from ccopt import cli, plots

    out = tmp_path / "run"
    run = ["run", "--schedule", "smoke", "--no-figures", "--no-progress", "--max-sim-s", "0.3"]
    assert cli.main([*run, "--out", str(out)]) == 3
    capsys.readouterr()

    def cut_short(record, path):
        path.write_bytes(b"GIF89a")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(plots, "animation", cut_short)
    assert cli.main(["plot", str(out)]) == 1
    line = f"ccopt plot: cannot draw the figures of {str(out)!r}: OSError: [Errno 28] No space left on device"
    assert capsys.readouterr().err.splitlines() == [line]
    assert not list(out.glob("*.png")) and not list(out.glob("*.gif"))
