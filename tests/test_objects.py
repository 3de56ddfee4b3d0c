"""Object library: shapes, physical properties and validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import geometry
from ccopt.objects import (
    OBJECT_NAMES,
    PAPER_OBJECT_NAMES,
    PlanarObject,
    from_vertices,
    make_object,
    rectangle,
    regular_polygon,
)


def _side_lengths(obj: PlanarObject) -> np.ndarray:
    return np.linalg.norm(obj.faces[:, 1] - obj.faces[:, 0], axis=1)


@pytest.mark.parametrize("name", OBJECT_NAMES)
def test_library_objects_are_convex_ccw_and_centred(name: str) -> None:
    obj = make_object(name)
    assert geometry.is_convex(obj.vertices)
    assert geometry.signed_area(obj.vertices) > 0.0
    np.testing.assert_allclose(geometry.centroid(obj.vertices), 0.0, atol=1e-12)
    assert obj.mu_hand == 0.5 and obj.mu_ground == 0.8
    assert _side_lengths(obj).min() >= 0.07 and _side_lengths(obj).max() <= 0.19


def test_paper_objects_have_the_papers_dimensions_and_masses() -> None:
    expected = {
        "paper-triangle": ([0.128, 0.134, 0.134], 0.195),
        "paper-square": ([0.10] * 4, 0.244),
        "paper-rectangle": ([0.11, 0.11, 0.18, 0.18], 0.445),
        "paper-pentagon": ([0.08] * 5, 0.278),
        "paper-hexagon": ([0.07] * 6, 0.310),
    }
    assert set(PAPER_OBJECT_NAMES) == set(expected)
    for name, (sides, mass) in expected.items():
        obj = make_object(name)
        np.testing.assert_allclose(np.sort(_side_lengths(obj)), sides, atol=1e-12)
        assert obj.mass == mass


def test_added_mass_and_overrides() -> None:
    assert make_object("paper-pentagon", added_mass=0.5).mass == pytest.approx(0.778)
    big = make_object("hexagon", side=0.12, mass=0.4, mu_hand=0.3, mu_ground=0.6)
    np.testing.assert_allclose(_side_lengths(big), 0.12)
    assert (big.mass, big.mu_hand, big.mu_ground) == (0.4, 0.3, 0.6)
    np.testing.assert_allclose(
        np.sort(_side_lengths(make_object("rectangle", width=0.1, height=0.05))),
        [0.05, 0.05, 0.1, 0.1],
    )


def test_inertia_of_a_square_lamina() -> None:
    side, mass = 0.1, 0.244
    assert make_object("paper-square").inertia == pytest.approx(mass * side**2 / 6.0)


def test_regular_polygon_face_zero_is_the_bottom() -> None:
    obj = regular_polygon(5, 0.08, 0.3)
    np.testing.assert_allclose(obj.face_normal(0), [0.0, -1.0], atol=1e-12)
    assert obj.vertices[0, 1] == pytest.approx(obj.vertices[:, 1].min())


def test_clockwise_vertices_are_reordered_and_offset_vertices_recentred() -> None:
    square_cw = [(1.0, 1.0), (1.1, 1.0), (1.1, 0.9), (1.0, 0.9)]
    assert geometry.signed_area(square_cw) < 0.0
    obj = from_vertices(square_cw, mass=0.2)
    assert geometry.signed_area(obj.vertices) > 0.0
    np.testing.assert_allclose(obj.vertices.mean(axis=0), 0.0, atol=1e-12)
    assert not obj.vertices.flags.writeable


def test_equal_objects_compare_and_hash_equal() -> None:
    assert make_object("square") == make_object("square")
    assert hash(make_object("square")) == hash(make_object("square"))
    assert make_object("square") != make_object("square", mass=1.0)


@pytest.mark.parametrize(
    ("vertices", "message"),
    [
        ([(0, 0), (1, 0)], "at least 3 vertices"),
        ([(0, 0), (0.1, 0), (np.nan, 0.1)], "finite"),
        ([(0, 0), (0.1, 0), (0.05, 0.02), (0.1, 0.1), (0, 0.1)], "convex"),
        ([(0, 0), (0.1, 0.1), (0.1, 0), (0, 0.1)], "convex"),
        ([(0, 0), (0.1, 0), (0.1, 0.005), (0, 0.1)], r"0.01 m to 1 m long .*got a face of 0.005 m"),
        ([(0, 0), (1e297, 0), (0, 1e297)], r"0.01 m to 1 m long .*got a face of 1.41e\+297 m"),
        ([0.0, 0.1, 0.2], "shape"),
    ],
)
def test_bad_vertices_raise_value_error(vertices: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        from_vertices(vertices, mass=0.2)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"mass": 0.0}, "mass must be a positive.*got 0.0"),
        ({"mass": -1.0}, "mass must be a positive.*got -1.0"),
        ({"mass": math.inf}, "mass.*inf"),
        ({"mu_hand": -0.1}, "mu_hand.*-0.1"),
        ({"mu_ground": math.nan}, "mu_ground.*nan"),
        ({"added_mass": -0.5}, "added_mass.*-0.5"),
        ({"side": 0.0}, "side.*0.0"),
    ],
)
def test_bad_values_raise_value_error_naming_them(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make_object("square", **kwargs)


def test_wrong_types_raise_type_error() -> None:
    with pytest.raises(TypeError, match="mass"):
        PlanarObject("x", [(0, 0), (0.1, 0), (0, 0.1)], mass="heavy")
    with pytest.raises(TypeError, match="name"):
        PlanarObject(3, [(0, 0), (0.1, 0), (0, 0.1)], mass=0.2)
    with pytest.raises(TypeError, match="vertices"):
        PlanarObject("x", [("a", 0), (0.1, 0), (0, 0.1)], mass=0.2)
    with pytest.raises(TypeError, match="side"):
        make_object("paper-square", side=0.2)
    with pytest.raises(TypeError, match="n_sides"):
        regular_polygon(4.0, 0.1, 0.2)


def test_unknown_name_lists_the_valid_ones() -> None:
    with pytest.raises(ValueError, match=r"'octagon'.*paper-hexagon"):
        make_object("octagon")


def test_face_index_is_validated() -> None:
    with pytest.raises(ValueError, match=r"face must be in \[0, 3\].*got 4"):
        rectangle(0.1, 0.05, 0.2).face_normal(4)
