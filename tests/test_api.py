"""The package's public face: its version and the names a researcher uses."""

import subprocess
import sys
from importlib import metadata

import ccopt


def test_version_is_the_installed_distribution_s():
    assert ccopt.__version__ == metadata.version("ccopt")


def test_cli_prints_the_version():
    done = subprocess.run(
        [sys.executable, "-m", "ccopt.cli", "--version"], capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == f"ccopt {ccopt.__version__}"


def test_every_exported_name_resolves_to_its_definition():
    from ccopt import closed_loop, estimation, objects

    assert ccopt.Estimator is estimation.Estimator
    assert ccopt.make_object is objects.make_object
    assert ccopt.run is closed_loop.run
    for name in ccopt.__all__:
        assert getattr(ccopt, name) is not None
    assert sorted(ccopt.__all__) == dir(ccopt)


def test_importing_ccopt_loads_no_simulator_and_no_plotting():
    code = "import sys, ccopt; print(any(m in sys.modules for m in ('mujoco', 'matplotlib', 'casadi')))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"


def test_the_library_does_not_depend_on_its_studies():
    code = "import sys, ccopt.experiment, ccopt.cli, ccopt.plots; print('studies' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"


def test_figures_and_summaries_take_a_run_s_own_results_in_memory():
    from ccopt import metrics, plots
    from ccopt.closed_loop import Supervision

    schedule = ccopt.load_schedule("smoke")
    params = ccopt.LoopParams(supervision=Supervision(max_time=0.8))
    done = ccopt.run_experiment(ccopt.make_object("paper-square"), schedule, params, seed=2)
    assert done.folder is None and len(done.result.samples["time"]) > 50
    summary = metrics.summarize(done.result, schedule)  # the run's own result and its schedule
    assert summary == {key: done.summary[key] for key in summary}
    for run in (done, done.result):
        traces = plots.estimation_traces(run)
        true = next(line for line in traces.axes[0].get_lines() if line.get_label() == "true")
        assert len(true.get_xdata()) == len(done.result.samples["time"])
    title = plots.friction_cones(done).get_suptitle()
    assert "paper-square" in title and "true" in title  # the object of the run's metadata
