"""ccopt.feasibility_map against independent truths: direct LP calls, the object's own geometry and
the start's equilibrium, and the estimate it was judged at."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import closed_loop, experiment, feasibility_map, statics
from ccopt.modes import Motion
from ccopt.objects import make_object
from ccopt.schedule import load_schedule


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> experiment.Experiment:
    folder = tmp_path_factory.mktemp("map") / "run"
    obj = make_object("paper-triangle")
    params = closed_loop.LoopParams()
    return experiment.run_experiment(obj, load_schedule("smoke"), params, seed=2, folder=folder)


def test_the_run_folder_keeps_the_maps_it_computed(run: experiment.Experiment) -> None:
    loaded = feasibility_map.load(run.folder)
    assert loaded is not None
    for name in ("theta_o", "s_h", "estimated", "true", "true_valid"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(run.feasibility_map, name))
    assert loaded.motions == tuple(m.value for m in feasibility_map.MOTIONS)


def test_true_margins_are_direct_lp_calls_where_the_configuration_exists(run: experiment.Experiment) -> None:
    fmap, obj, params = run.feasibility_map, make_object("paper-triangle"), closed_loop.LoopParams()
    frame = experiment.oracle_frame(obj, params, run.result.hand_angle_range)
    rng = np.random.default_rng(0)
    for _ in range(20):
        k, i, j = (int(rng.integers(n)) for n in fmap.true.shape)
        theta, s_h = fmap.theta_o[i], fmap.s_h[j]
        on_face = frame.truth.s_h_range[0] - 1e-9 <= s_h <= frame.truth.s_h_range[1] + 1e-9
        on_vertex = frame.vertex_range[0] - 1e-9 <= theta <= frame.vertex_range[1] + 1e-9
        assert fmap.true_valid[i, j] == (on_face and on_vertex)
        if not (on_face and on_vertex):
            assert math.isnan(fmap.true[k, i, j])
            continue
        motion = Motion(fmap.motions[k])
        truth = frame.truth.statics
        expected = statics.best_wrench(truth, theta, s_h, motion, frame.lever, frame.forces).margin
        assert fmap.true[k, i, j] == pytest.approx(expected, abs=1e-9)


def test_the_start_is_inside_both_pivot_regions_and_the_estimate_agrees_where_the_run_went(
    run: experiment.Experiment,
) -> None:
    """The object starts in equilibrium, held by the hand (the plants start it so): pivoting is
    possible there with margin on the true statics and on the estimated ones; over the tilts the run
    visited (the smoke schedule's pivots, ±7.2° about 17.2°) the estimated pivot region is the true
    one at nine grid points in ten."""
    fmap = run.feasibility_map
    i = int(np.argmin(np.abs(fmap.theta_o - math.radians(17.2))))
    j = int(np.argmin(np.abs(fmap.s_h - 0.0)))
    assert fmap.true[0, i, j] >= fmap.min_margin
    assert fmap.estimated[0, i, j] >= fmap.min_margin
    visited = np.abs(fmap.theta_o - math.radians(17.2)) <= math.radians(7.2)
    region = fmap.true_valid & visited[:, None]
    estimated, true = (values[0][region] >= fmap.min_margin for values in (fmap.estimated, fmap.true))
    assert np.mean(estimated == true) >= 0.9


def test_the_figure_is_drawn_for_a_run_without_estimate(tmp_path) -> None:
    obj, params = make_object("paper-square"), closed_loop.LoopParams()
    frame = experiment.oracle_frame(obj, params, (-0.5, 0.8))
    fmap = feasibility_map.of_run(
        obj, frame.start, params.hand, None, (-0.5, 0.8), frame.lever, frame.forces, 1.0, frame.vertex_range
    )
    assert np.all(np.isnan(fmap.estimated)) and math.isnan(fmap.estimated_at[0])
    path = tmp_path / "map.png"
    feasibility_map.draw(fmap, path)
    assert path.stat().st_size > 10_000


def test_every_panel_shows_the_grid_and_only_the_outer_ones_label_their_ticks(
    run: experiment.Experiment,
) -> None:
    """The panels are not shared axes (sharing passes every limit change on to the nine others), yet
    each shows the whole grid, θ_o in degrees and s_h in mm, and tick labels only along the left column
    and the bottom row, as shared axes would."""
    fmap = run.feasibility_map
    figure = feasibility_map.draw(fmap)
    figure.canvas.draw()
    panels = [ax for ax in figure.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 2 * len(fmap.motions)
    extent = (np.degrees(fmap.theta_o[[0, -1]]), 1e3 * fmap.s_h[[0, -1]])
    for k, ax in enumerate(panels):
        row, column = divmod(k, 2)
        np.testing.assert_allclose(ax.get_xlim(), extent[0])
        np.testing.assert_allclose(ax.get_ylim(), extent[1])
        labelled = [bool(axis.get_ticklabels()) for axis in (ax.xaxis, ax.yaxis)]  # the visible ones
        assert labelled == [row == len(fmap.motions) - 1, column == 0], k


def test_an_unreadable_map_file_is_a_value_error_naming_it(tmp_path) -> None:
    (tmp_path / feasibility_map.FILE_NAME).write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"feasibility_map\.npz"):
        feasibility_map.load(tmp_path)
    assert feasibility_map.load(tmp_path / "missing") is None
