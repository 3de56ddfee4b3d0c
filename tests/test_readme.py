"""The README, followed as a new user would: its ``console`` blocks run as written (each ``$ ccopt ...``
line, in order, in a fresh folder) and print every line the README shows (``…`` marks lines left
out; of the wall time only its label); ``make demo`` is the demo command it shows; its Python examples
run; its settings and schedule files load; its tables of record keys and objects are the ones ccopt
has. The commands are read from the README, so a README that no longer tells the truth fails here."""

import importlib.util
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
TEXT = README.read_text(encoding="utf-8")


def blocks(language: str) -> list[str]:
    """The fenced blocks of ``language`` in the README, in order."""
    return re.findall(rf"^```{language}\n(.*?)^```", TEXT, flags=re.MULTILINE | re.DOTALL)


def sessions() -> list[tuple[str, list[str]]]:
    """``(command, lines it shows)`` of every ``$`` line of the console blocks, in order."""
    found = []
    for block in blocks("console"):
        for line in block.splitlines():
            if line.startswith("$ "):
                found.append((line[2:], []))
            elif found and line.strip():
                found[-1][1].append(line)
    return found


ELIDED = "…"
"""A shown line that stands for lines left out."""


def collapsed(line: str) -> str:
    """``line`` with every run of white space one space, and none at its ends."""
    return " ".join(line.split())


def shows(printed: list[str], line: str) -> bool:
    """Whether a shown line is one of the printed lines (white space collapsed); of the wall time
    (this machine's) only its label, the text up to the first gap of two spaces, must begin one."""
    if "wall time" in line:
        label = re.split(r"\s{2,}", line.strip())[0]
        return any(candidate.startswith(label) for candidate in printed)
    return collapsed(line) in printed


def test_the_readme_has_the_two_set_up_commands_and_runnable_sessions():
    (setup, *_) = blocks("sh")
    assert "make demo" in setup and "make test" in setup
    commands = [command for command, _ in sessions()]
    for needed in ("ccopt run", "ccopt plot", "ccopt view", "ccopt objects", "ccopt study", "--config"):
        assert any(needed in command for command in commands), needed


def test_every_console_command_runs_and_shows_what_the_readme_shows(tmp_path):
    if importlib.util.find_spec("rerun") is None:
        pytest.skip("rerun-sdk is not installed (ccopt view needs it)")
    for command, shown in sessions():
        words = shlex.split(command)
        assert words[0] == "ccopt", command
        done = subprocess.run(
            [sys.executable, "-m", "ccopt.cli", *words[1:]],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0, f"{command}: {done.stderr}"
        printed = [collapsed(line) for line in done.stdout.splitlines()]
        for line in shown:
            if line.strip() != ELIDED:
                assert shows(printed, line), f"{command}: {line!r} not printed:\n{done.stdout}"
    assert (tmp_path / "runs" / "first" / "run.rrd").stat().st_size > 0
    assert (tmp_path / "runs" / "again" / "record.npz").is_file()
    assert {path.name for path in (tmp_path / "runs" / "demo").iterdir()} >= {
        "record.npz",
        "meta.json",
        "summary.json",
        "estimation.png",
        "friction_cones.png",
        "control.png",
        "animation.gif",
    }


def test_make_demo_runs_the_demo_command_the_readme_shows():
    makefile = (README.parent / "Makefile").read_text(encoding="utf-8")
    (recipe,) = re.findall(r"^demo:.*\n\t\$\(PY\) -m ccopt\.cli (.+)$", makefile, flags=re.MULTILINE)
    demo = [command for command, _ in sessions() if "--out runs/demo" in command]
    assert demo == [f"ccopt {recipe}"]


@pytest.mark.parametrize("index", range(len(blocks("python"))))
def test_every_python_example_runs(tmp_path, index):
    done = subprocess.run(
        [sys.executable, "-c", blocks("python")[index]],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr


def test_the_gradient_example_prints_an_agreement_to_finite_differences(tmp_path):
    (example,) = [block for block in blocks("python") if "motion_vectors" in block]
    done = subprocess.run([sys.executable, "-c", example], capture_output=True, text=True, timeout=120)
    assert float(done.stdout.split()[-1]) < 1e-8


def test_the_record_table_lists_every_array_a_run_records_with_its_unit():
    from ccopt.experiment import RECORD_UNITS

    rows = dict(re.findall(r"^\| `(\w+)` \| (.+) \|$", TEXT, flags=re.MULTILINE))
    for key, unit in RECORD_UNITS.items():
        assert rows.get(key) == unit, key


def test_the_objects_table_is_the_library():
    from ccopt import objects

    listed = re.findall(r"^((?:paper-)?[a-z]+) +(\d) ", TEXT, flags=re.MULTILINE)
    assert [name for name, _ in listed] == list(objects.OBJECT_NAMES)
    for name, faces in listed:
        assert objects.make_object(name).n_faces == int(faces)


def test_the_settings_and_schedule_files_load_as_the_readme_says(tmp_path):
    from ccopt import config, objects
    from ccopt.schedule import load_schedule

    (settings,) = [block for block in blocks("yaml") if "params:" in block]
    (schedule,) = [block for block in blocks("yaml") if "steps:" in block]
    (tmp_path / "settings.yaml").write_text(settings, encoding="utf-8")
    (tmp_path / "schedule.yaml").write_text(schedule, encoding="utf-8")
    run = config.build(config.read_file(tmp_path / "settings.yaml"))
    assert run.obj.mass == pytest.approx(objects.make_object("paper-square").mass + 0.5)
    assert (run.obj.mu_hand, run.seed, run.params.hand.half_length) == (0.4, 3, 0.025)
    assert load_schedule(tmp_path / "schedule.yaml").name == "my-sequence"
