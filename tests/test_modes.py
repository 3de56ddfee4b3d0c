"""Commanded motions remove exactly the rows that would block them."""

import pytest

from ccopt import modes
from ccopt.contact import Row
from ccopt.modes import ContactMode, Motion


def test_each_slide_removes_exactly_its_row():
    for motion, row in [
        (Motion.SLIDE_HAND_POS, Row.HAND_SLIDE_POS),
        (Motion.SLIDE_HAND_NEG, Row.HAND_SLIDE_NEG),
        (Motion.SLIDE_GROUND_POS, Row.GROUND_SLIDE_POS),
        (Motion.SLIDE_GROUND_NEG, Row.GROUND_SLIDE_NEG),
    ]:
        mask = modes.kept_rows(motion)
        assert not mask[row]
        assert mask.sum() == len(Row) - 1


def test_pivot_and_hold_keep_every_row():
    assert modes.kept_rows(Motion.PIVOT).all()
    assert modes.kept_rows("hold").all()


def test_configuration_of_a_motion():
    assert modes.configuration(Motion.SLIDE_GROUND_NEG).ground_mode == ContactMode.SLIDE_NEG
    assert modes.configuration(Motion.SLIDE_GROUND_NEG).hand_mode == ContactMode.STICK


def test_signed_helpers_and_errors():
    assert modes.slide_hand(0.01) is Motion.SLIDE_HAND_POS
    assert modes.slide_ground(-0.01) is Motion.SLIDE_GROUND_NEG
    with pytest.raises(ValueError, match="non-zero"):
        modes.slide_hand(0.0)
    with pytest.raises(ValueError, match="unknown motion 'twirl'"):
        modes.kept_rows("twirl")


def test_slides_are_the_motions_whose_configuration_moves_a_contact():
    """A motion is a slide exactly where its contact configuration sets the hand or the ground sliding."""
    for motion in Motion:
        configuration = modes.configuration(motion)
        contacts = (configuration.hand_mode, configuration.ground_mode)
        moving = any(mode != ContactMode.STICK for mode in contacts)
        assert (motion in modes.SLIDES) == moving, motion


def test_a_slide_keeps_the_position_of_the_contact_its_configuration_holds_sticking():
    """A slide's kept coordinate is ``s_h`` where its configuration keeps the hand sticking and ``s_g``
    where it keeps the ground sticking; a motion that slides nothing keeps none."""
    for motion in Motion:
        configuration = modes.configuration(motion)
        if motion not in modes.SLIDES:
            expected = None
        elif configuration.hand_mode == ContactMode.STICK:
            expected = modes.S_H
        else:
            assert configuration.ground_mode == ContactMode.STICK, motion
            expected = modes.S_G
        assert modes.kept_coordinate(motion) == expected, motion
        assert modes.kept_coordinate(modes.kind_of(motion)) == expected, motion


@pytest.mark.parametrize("motion", list(Motion))
def test_a_configuration_slides_exactly_when_its_motion_removes_a_friction_row(motion):
    """The configuration a motion commands slides a contact iff the motion is one of :data:`SLIDES`
    (it removes a friction row)."""
    assert modes.configuration(motion).slides is (motion in modes.SLIDES)
