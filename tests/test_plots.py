"""The figures draw what the record holds, in degrees and mm, and survive empty records."""

import subprocess
import sys

import numpy as np
import pytest
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from PIL import Image

from ccopt import geometry, plots, replay
from ccopt.record import RecordWriter, load_record

DT = 0.01
MASS, MU_HAND, MU_GROUND = 0.3, 0.5, 0.3
SIDE = 0.1
STEPS = (  # kind, coordinate, commanded delta (SI), realised share, start, end (s)
    ("pivot", 0, np.deg2rad(7.2), 1.0, 0.5, 2.0),
    ("slide_hand", 1, 0.010, 1.0, 2.5, 4.0),
    ("slide_ground", 2, 0.010, 0.9, 4.5, 6.0),
)
CODES = {"pivot": 1, "slide_hand": 2, "slide_ground": 3}


def _ramp(t, start, end, change):
    return change * np.clip((t - start) / (end - start), 0.0, 1.0)


def _samples(duration=6.5, seed=0):
    """A square pivoted about its lower-left vertex, hand on top: a pivot, a hand slide, a ground slide.

    Truth follows the paper's kinematics exactly; estimates are truth plus noise once valid (0.3 s).
    """
    rng = np.random.default_rng(seed)
    time = np.arange(0.0, duration, DT)
    n = len(time)
    true = np.zeros((n, 3))
    true[:, 1] = -0.5 * SIDE
    for _, k, delta, share, start, end in STEPS:
        true[:, k] += _ramp(time, start, end, share * delta)
    d = np.full(n, SIDE)
    modes = np.zeros((n, 3), dtype=np.int8)
    for _, k, _, _, start, end in STEPS[1:]:
        modes[(time > start) & (time < end), 0 if k == 1 else 2] = 1
    contacts = np.ones((n, 2), dtype=bool)
    contacts[:5, 0] = False
    valid = time >= 0.3
    weight = MASS * geometry.GRAVITY
    samples = []
    for i, t in enumerate(time):
        theta, s_h, s_g = true[i]
        pose = geometry.hand_pose_from_contact(theta, s_h, d[i], (s_g, 0.0))
        measured = pose + rng.normal(0.0, [2e-4, 2e-4, 1e-3])
        if modes[i, 2]:
            f_y = -8.0 + rng.normal(0.0, 0.2)
            world = np.array([MU_GROUND * (weight - f_y) - abs(rng.normal(0.0, 0.05)), f_y, 0.0])
            wrench = geometry.wrench_world_to_hand(measured[2], world)
        else:
            f_n = 5.0 + rng.normal(0.0, 0.1)
            wrench = np.array([f_n, MU_HAND * f_n if modes[i, 0] else rng.normal(0.0, 0.3), 0.0])
        noise = rng.normal(0.0, [np.deg2rad(0.5), 1e-3, 1e-3])
        step = max([j for j, s in enumerate(STEPS) if t >= s[4]], default=-1)
        active = step >= 0 and t < STEPS[step][5]
        command = np.full(3, np.nan)
        if active:
            _, k, delta, _, start, _ = STEPS[step]
            command = true[i] + noise
            command[k] = true[round(start / DT), k] + delta
        mu_g = MU_GROUND if t >= 1.0 else np.nan
        samples.append(
            {
                "time": t,
                "hand_pose": measured,
                "hand_wrench": wrench,
                "target": measured,
                "est_coordinates": true[i] + noise if valid[i] else np.zeros(3),
                "est_d": d[i] + rng.normal(0.0, 1e-3),
                "est_kinematics_valid": valid[i],
                "est_mu_h": 0.45 + 0.05 * min(t / 3.0, 1.0) if valid[i] else np.nan,
                "est_ground_rows": np.array([[1.0, mu_g], [-1.0, mu_g]]),
                "est_ground_bounds": np.full(2, mu_g * weight),
                "est_modes": modes[i],
                "step_index": np.int16(step),
                "motion": np.int8(CODES[STEPS[step][0]] if active else 0),
                "command_targets": command,
                "qp_slack": 0.0,
                "qp_feasible": True,
                "true_coordinates": true[i],
                "true_d": d[i],
                "true_modes": modes[i],
                "true_contacts": contacts[i],
                "true_hand_pose": pose,
                "true_hand_wrench": wrench,
            }
        )
    return samples


def _meta():
    half = 0.5 * SIDE
    return {
        "object": {
            "name": "square",
            "vertices": [[-half, -half], [half, -half], [half, half], [-half, half]],
            "mass": MASS,
            "mu_hand": MU_HAND,
            "mu_ground": MU_GROUND,
        },
        "params": {"l_h": 0.03, "start": {"hand_face": 2}},
    }


def _write(folder, samples, steps=True):
    writer = RecordWriter(folder, _meta())
    for sample in samples:
        writer.append(sample)
    if steps:
        writer.meta["steps"] = [
            {"index": j, "kind": kind, "delta": delta, "start_time": start, "end_time": end, "reached": True}
            for j, (kind, _, delta, _, start, end) in enumerate(STEPS)
        ]
    writer.close()
    return load_record(folder)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    return _write(tmp_path_factory.mktemp("run"), _samples())


@pytest.fixture(scope="module")
def empty(tmp_path_factory):
    return _write(tmp_path_factory.mktemp("empty"), [], steps=False)


def _line(ax, label):
    (line,) = [line for line in ax.get_lines() if line.get_label() == label]
    return line


def _texts(fig):
    return [text.get_text() for ax in fig.axes for text in ax.texts]


def test_estimation_traces_show_truth_and_valid_estimates_in_degrees_and_mm(run):
    fig = plots.estimation_traces(run)
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    valid = run["est_kinematics_valid"]
    for k, (ax, scale) in enumerate(zip(fig.axes, (180.0 / np.pi, 1000.0, 1000.0), strict=True)):
        np.testing.assert_allclose(_line(ax, "true").get_ydata(), scale * run["true_coordinates"][:, k])
        estimate = np.where(valid, scale * run["est_coordinates"][:, k], np.nan)
        np.testing.assert_allclose(_line(ax, "estimated").get_ydata(), estimate)
        assert len(ax.patches) == 1  # the one step that commands this coordinate is shaded
        (start, _), (end, _) = ax.patches[0].get_bbox().get_points()
        assert start == pytest.approx(STEPS[k][4], abs=DT) and end == pytest.approx(STEPS[k][5], abs=2 * DT)


def test_error_boxes_pool_records_and_mark_the_median(run):
    fig = plots.estimation_error_boxes([run, run])
    assert len(fig.axes) == 3
    valid = run["est_kinematics_valid"]
    error = np.abs(run["est_coordinates"][valid] - run["true_coordinates"][valid]) * [180 / np.pi, 1e3, 1e3]
    for k, ax in enumerate(fig.axes):
        (median,) = [line for line in ax.get_lines() if line.get_color() == plots.ESTIMATE_COLOR]
        np.testing.assert_allclose(median.get_ydata(), np.median(error[:, k]))


def test_friction_cones_colour_points_by_true_mode(run):
    fig = plots.friction_cones(run)
    hand, ground = fig.axes
    for ax, contact, mode in (
        (hand, run["true_contacts"][:, 0], 0),
        (ground, run["true_contacts"].all(1), 2),
    ):
        sticking, sliding = ax.collections
        truly_sliding = contact & (run["true_modes"][:, mode] != 0)
        assert len(sliding.get_offsets()) == truly_sliding.sum() > 0
        assert len(sticking.get_offsets()) == (contact & ~truly_sliding).sum()
        np.testing.assert_allclose(sliding.get_facecolor()[0], to_rgba(plots.SLIDING_COLOR))
    hand_sliding = run["true_contacts"][:, 0] & (run["true_modes"][:, 0] != 0)
    np.testing.assert_allclose(hand.collections[1].get_offsets(), run["hand_wrench"][hand_sliding, :2])


def _slopes(ax, gid):
    lines = [line for line in ax.get_lines() if line.get_gid() == gid]
    return sorted(np.diff(line.get_ydata())[0] / np.diff(line.get_xdata())[0] for line in lines)


def _on_rows(ax, gid, rows, bounds):
    """Each ``gid`` line of ``ax`` lies on one row's line ``a·f = b``."""
    lines = [line for line in ax.get_lines() if line.get_gid() == gid]
    assert len(lines) == len(rows)
    for line, row, bound in zip(lines, rows, bounds, strict=True):
        np.testing.assert_allclose(line.get_xydata() @ row, bound)


def test_friction_cones_draw_the_true_cones_beside_the_estimate_of_the_instant_they_name(run):
    hand, ground = plots.friction_cones(run).axes
    np.testing.assert_allclose(_slopes(hand, "estimated"), [-run["est_mu_h"][-1], run["est_mu_h"][-1]])
    np.testing.assert_allclose(_slopes(hand, "true"), [-MU_HAND, MU_HAND])
    _on_rows(ground, "estimated", run["est_ground_rows"][-1], run["est_ground_bounds"][-1])
    weight = MASS * 9.81  # the ground slides when |f_x| > μ_g (m g − f_y)
    _on_rows(ground, "true", [[1.0, MU_GROUND], [-1.0, MU_GROUND]], [MU_GROUND * weight] * 2)
    title = plots.friction_cones(run).get_suptitle()
    assert "Fig. 7" in title and f"t = {run['time'][-1]:.2f} s" in title and "last" in title
    early = plots.friction_cones(run, at=2.0)
    k = np.flatnonzero(run["time"] <= 2.0)[-1]
    assert f"t = {run['time'][k]:.2f} s" in early.get_suptitle()
    np.testing.assert_allclose(_slopes(early.axes[0], "estimated"), [-run["est_mu_h"][k], run["est_mu_h"][k]])


def test_every_figure_names_the_paper_figure_it_reproduces(run):
    for draw, number in (
        (plots.estimation_traces, "Fig. 6a"),
        (plots.estimation_error_boxes, "Fig. 6b"),
        (plots.estimation_figure, "Fig. 6"),
        (plots.friction_cones, "Fig. 7"),
        (plots.control_errors, "Fig. 8a"),
        (plots.realised_histogram, "Fig. 8b"),
        (plots.control_figure, "Fig. 8"),
    ):
        assert draw(run).get_suptitle().startswith(number + ":"), draw.__name__


def test_ground_panel_shows_the_world_hand_force(run):
    ground = plots.friction_cones(run).axes[1]
    theta, (f_n, f_t) = run["hand_pose"][:, 2], run["hand_wrench"][:, :2].T
    world = np.column_stack(
        (f_n * np.sin(theta) + f_t * np.cos(theta), -f_n * np.cos(theta) + f_t * np.sin(theta))
    )
    sliding = run["true_modes"][:, 2] != 0
    np.testing.assert_allclose(ground.collections[1].get_offsets(), world[sliding])


def test_control_errors_draw_one_line_per_commanded_step(run):
    fig = plots.control_errors(run)
    assert len(fig.axes) == 3
    for (_, k, _, _, start, end), ax, scale in zip(STEPS, fig.axes, (180 / np.pi, 1e3, 1e3), strict=True):
        (line,) = [line for line in ax.get_lines() if line.get_linestyle() == "-"]
        during = run["motion"] == k + 1
        np.testing.assert_allclose(line.get_xdata(), run["time"][during])
        error = scale * (run["command_targets"][during, k] - run["true_coordinates"][during, k])
        np.testing.assert_allclose(line.get_ydata(), error, atol=1e-9)
        assert line.get_xdata()[0] == pytest.approx(start, abs=DT) and line.get_xdata()[-1] < end


def test_histogram_counts_every_step_of_every_record(run):
    fig = plots.realised_histogram([run, run])
    (ax,) = fig.axes
    counts = [patch.get_height() for patch in ax.patches]
    assert sum(counts) == 2 * len(STEPS)
    (one,) = ax.get_lines()
    assert one.get_linestyle() == "--" and list(one.get_xdata()) == [1.0, 1.0]
    heights = {round(patch.get_x() + 0.5 * patch.get_width(), 6): patch.get_height() for patch in ax.patches}
    assert heights[0.9] == 2 and heights[1.0] == 4  # the ground slides realised 90 %, the others all


def test_animation_scene_puts_the_hand_on_the_object_face(run):
    frames = np.array([0, 150, 350, 600])
    for i, frame in zip(frames, replay.scene(run, frames), strict=True):
        polygon, (end_a, end_b) = frame.object, frame.hand
        np.testing.assert_allclose(polygon.min(axis=0)[1], 0.0, atol=1e-12)  # resting on the ground
        np.testing.assert_allclose(frame.r_o, (run["true_coordinates"][i, 2], 0.0), atol=1e-12)
        top = polygon[2:4]  # the hand face (2) lies on the hand segment's line
        normal = geometry.hand_normal(run["true_hand_pose"][i, 2])
        np.testing.assert_allclose((top - end_a) @ normal, 0.0, atol=1e-12)
        np.testing.assert_allclose((end_b - end_a) @ normal, 0.0, atol=1e-12)


def test_ccopt_plot_of_a_run_writes_all_five_figures(tmp_path, capsys):
    """``ccopt plot`` of a run folder (the stills drawn in this process, the GIF and the feasibility map
    in its forked worker) lists the five figures, each an image PIL reads whole."""
    from ccopt import cli

    folder = tmp_path / "run"
    run = ["run", "--schedule", "smoke", "--max-sim-s", "1", "--no-figures", "--no-progress"]
    assert cli.main([*run, "--out", str(folder)]) == 3  # the time limit ran out
    capsys.readouterr()
    assert cli.main(["plot", str(folder)]) == 0
    names = [*plots.FIGURES, "animation.gif", "feasibility_map.png"]
    assert capsys.readouterr().out.splitlines() == ["figures: " + ", ".join(str(folder / n) for n in names)]
    for name in names:
        with Image.open(folder / name) as image:
            image.verify()


def test_drawing_a_run_leaves_the_settings_and_the_estimation_unimported():
    """What ``ccopt plot`` imports before it forks its worker, and what the worker imports to draw the
    feasibility map, leaves out the run settings, the statics, the estimator and the controller: only
    running (and computing the maps) needs them."""
    code = (
        "import sys, ccopt.cli, ccopt.plots, ccopt.feasibility_map; "
        "print(*sorted(m for m in sys.modules if m.split('.')[:2] in "
        "(['ccopt', 'config'], ['ccopt', 'statics'], ['ccopt', 'estimation'], ['ccopt', 'control'])))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == ""
    control = subprocess.run(
        [sys.executable, "-c", code.replace("ccopt.cli", "ccopt.experiment")],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "ccopt.statics" in control.stdout.split()  # the check sees an import where there is one


def test_write_figures_writes_images_pil_can_open(tmp_path):
    short = _write(tmp_path / "run", _samples()[::20])
    paths = plots.write_figures(short, tmp_path / "figures")
    assert [path.name for path in paths] == [
        "estimation.png",
        "friction_cones.png",
        "control.png",
        "animation.gif",
    ]
    for path in paths:
        assert path.stat().st_size > 0
        with Image.open(path) as image:
            image.verify()
    duration = short["time"][-1] - short["time"][0]
    with Image.open(paths[-1]) as gif:
        assert gif.width >= 640
        shown = [gif.seek(k) or gif.info["duration"] for k in range(gif.n_frames)]
    speed, count = plots.playback(duration, plots.MAX_FRAMES)
    assert len(shown) == count and set(shown) == {1000 * plots.FRAME_S}
    # playback proportional to simulated time: the GIF lasts the run's time over the stated speed
    assert abs(sum(shown) / 1000 * speed - duration) <= speed * plots.FRAME_S
    assert paths[-1].stat().st_size < 2_000_000


@pytest.mark.parametrize("name", list(plots.FIGURES))
def test_a_still_is_saved_with_the_pixels_savefig_gives(run, tmp_path, name):
    """save_png draws once what Matplotlib's savefig draws twice (a constrained layout pass, then
    the rendering): the same image, pixel for pixel, and the figure keeps its layout engine."""
    draw = plots.FIGURES[name]
    draw(run).savefig(tmp_path / "savefig.png", dpi=80)
    figure = draw(run)
    assert figure.get_layout_engine() is not None
    assert plots.save_png(figure, tmp_path / name, dpi=80) == tmp_path / name
    with Image.open(tmp_path / "savefig.png") as expected, Image.open(tmp_path / name) as saved:
        width, height = figure.get_size_inches() * 80
        assert saved.size == expected.size == (round(width), round(height))
        assert np.array_equal(np.asarray(saved), np.asarray(expected))


def test_the_gif_shows_each_frame_as_given(tmp_path):
    """Frames that keep only their changed pixels (the rest transparent) decode to the still image
    with each part over its region: a square moving over a two-colour background and back, a pixel
    changing colour and back, and a part unchanged (every colour is in the frames the palette is made
    from: the first, the middle and the last)."""
    still = np.zeros((40, 60, 3), dtype=np.uint8)
    still[:, 30:] = (200, 200, 255)
    still[35:, :] = (0, 128, 0)  # outside the region: the same in every frame
    left, top, right, bottom = region = (2, 1, 56, 32)
    parts = []
    for x in (0, 10, 20, 20, 10, 0):
        part = still[top:bottom, left:right].copy()
        part[5:25, x + 5 : x + 25] = (255, 0, 0)
        part[0, 0] = (255, 255, 255) if x == 20 else (0, 0, 0)
        parts.append(part)
    path = tmp_path / "moving.gif"
    plots._save_gif(path, Image.fromarray(still), region, [Image.fromarray(part) for part in parts], 0.1)
    with Image.open(path) as gif:
        shown = []
        for k in range(gif.n_frames):
            gif.seek(k)
            shown.append((np.asarray(gif.convert("RGB")), gif.info["duration"]))
    assert [duration for _, duration in shown] == [100] * len(parts)
    for (frame, _), part in zip(shown, parts, strict=True):
        expected = still.copy()
        expected[top:bottom, left:right] = part
        np.testing.assert_array_equal(frame, expected)


def _gif_frames(path):
    with Image.open(path) as gif:
        return [np.asarray(gif.seek(k) or gif.convert("RGB")) for k in range(gif.n_frames)]


def test_the_gif_reads_back_only_what_changes_and_loses_nothing(run, tmp_path, monkeypatch):
    """Read back over the whole canvas, the frames are the same: no moving artist or clock is drawn
    outside the region read back."""
    plots.animation(run, tmp_path / "region.gif")
    width, height = (round(inches * plots.GIF_DPI) for inches in plots.GIF_SIZE)
    monkeypatch.setattr(plots, "_region", lambda ax, texts: (0, 0, width, height))
    plots.animation(run, tmp_path / "whole.gif")
    region, whole = _gif_frames(tmp_path / "region.gif"), _gif_frames(tmp_path / "whole.gif")
    assert len(region) == len(whole) > 10
    for ours, theirs in zip(region, whole, strict=True):
        np.testing.assert_array_equal(ours, theirs)


def test_empty_and_short_records_say_no_data(empty, tmp_path):
    assert empty.data == {}
    short = _write(
        tmp_path / "short", [dict(s, est_kinematics_valid=False) for s in _samples(0.05)], steps=False
    )
    for record in (empty, short):
        for fig in (
            plots.estimation_traces(record),
            plots.estimation_error_boxes(record),
            plots.control_errors(record),
            plots.realised_histogram(record),
            plots.estimation_figure(record),
            plots.control_figure(record),
        ):
            assert {"no data", "no valid estimate"} & set(_texts(fig))
        plots.friction_cones(record)
        paths = plots.write_figures(record, tmp_path / record.folder.name / "figures")
        assert all(path.stat().st_size > 0 for path in paths)
    assert "no data" in _texts(plots.friction_cones(empty))


def test_a_record_with_sensor_dropouts_draws_every_figure_from_its_finite_samples(tmp_path):
    """A dropout or a dead sensor records NaN measurements: the figures leave those samples out."""
    samples = _samples()[::10]
    for sample in samples[20:35]:
        sample["hand_pose"] = np.full(3, np.nan)
        sample["hand_wrench"] = np.full(3, np.nan)
    record = _write(tmp_path / "dropouts", samples)
    fig = plots.friction_cones(record)
    hand, ground = fig.axes[:2]
    shown = sum(len(collection.get_offsets()) for collection in hand.collections)
    touching = record.data["true_contacts"][:, 0] & np.isfinite(record.data["hand_wrench"][:, 0])
    assert shown == int(touching.sum()) < len(samples) - 15
    assert np.isfinite(ground.get_xlim()).all() and np.isfinite(ground.get_ylim()).all()
    for path in plots.write_figures(record, tmp_path / "figures"):
        assert path.stat().st_size > 0


def _read_rrd(path):
    """Entity path → list of (time s, value) rows of an .rrd, read back with Rerun's own reader."""
    from rerun.chunk import RrdReader

    rows = {}
    for chunk in RrdReader(path).stream().to_chunks():
        batch = chunk.to_record_batch()
        if "sim_time" not in batch.schema.names:
            continue
        times = batch.column("sim_time").cast("int64").to_numpy() * 1e-9
        primary = (":strips", ":scalars", ":positions", ":vectors", ":text")
        value = next(name for name in batch.schema.names if name.endswith(primary))
        for time, item in zip(times, batch.column(value).to_pylist(), strict=True):
            rows.setdefault(str(chunk.entity_path), []).append((time, item))
    return {entity: sorted(found, key=lambda row: row[0]) for entity, found in rows.items()}


def test_view_writes_an_rrd_whose_series_and_scene_read_back(run, tmp_path):
    pytest.importorskip("rerun")
    from ccopt import view

    path = view.log_run(run, save=tmp_path / "run.rrd", spawn=False)
    found = _read_rrd(path)
    for entity in (
        "/scene/object",
        "/scene/hand",
        "/scene/contact/estimated",
        "/scene/cones/hand/true",
        "/scene/cones/ground/estimated",
        "/scene/force/measured",
        "/coordinates/s_g_mm/commanded",
        "/modes/ground_slide/true",
        "/qp/slack",
        "/command/motion",
    ):
        assert entity in found, entity
    times, theta = zip(*found["/coordinates/theta_o_deg/true"], strict=True)
    np.testing.assert_allclose(times, run["time"], atol=1e-9)
    np.testing.assert_allclose(np.ravel(theta), np.rad2deg(run["true_coordinates"][:, 0]))
    estimated = dict(found["/coordinates/s_h_mm/estimated"])
    valid = run["est_kinematics_valid"]
    assert len(estimated) == valid.sum()  # the estimate only where the kinematics are valid
    _time, (strip,) = found["/scene/object"][10]
    polygon = np.asarray(strip)[:-1]  # closed: the first vertex again
    faces = np.linalg.norm(np.roll(polygon, -1, axis=0) - polygon, axis=1)
    np.testing.assert_allclose(sorted(faces), [SIDE] * 4, atol=1e-6)  # the square of meta.json (float32)
    assert polygon[:, 1].min() == pytest.approx(0.0, abs=1e-6)  # on the ground
