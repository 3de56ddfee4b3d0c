"""The contact model, written once in CasADi (paper §III and eqs. 14–16).

Every function here is a ``casadi.Function`` built once at import and usable symbolically (compose
it into larger expressions, take Jacobians) or numerically through the NumPy wrappers at the bottom.
Frames and signs are those of :mod:`ccopt.geometry`: hand-frame vectors are ``(n, t, θ)`` and the
hand wrench ``w = (f_n, f_t, τ)`` is the wrench the hand exerts on the object.

Generalized friction cone
    Six linear rows ``N w ≤ b`` (hand frame). Row ``k`` is the LHS of one complementarity condition
    of the paper written as ``b_k − N_k w ≥ 0``; it is *tight* exactly when the motion it is
    complementary to may happen, so each row is named after the motion it **blocks**:

    =====================  ==========================================  ===================
    row                    inequality (≥ 0 inside the cone)            paper
    =====================  ==========================================  ===================
    ``HAND_SLIDE_POS``     ``μ_h f_n + f_t``        blocks ``ṡ_h > 0``  eq. 5
    ``HAND_SLIDE_NEG``     ``μ_h f_n − f_t``        blocks ``ṡ_h < 0``  eq. 6
    ``HAND_PIVOT_POS``     ``l_h f_n + τ``          blocks ``Δθ > 0``   eq. 8 (see below)
    ``HAND_PIVOT_NEG``     ``l_h f_n − τ``          blocks ``Δθ < 0``   eq. 7 (see below)
    ``GROUND_SLIDE_POS``   ``−μ_g F_y − F_x``       blocks ``ṡ_g > 0``  eq. 12 (see below)
    ``GROUND_SLIDE_NEG``   ``−μ_g F_y + F_x``       blocks ``ṡ_g < 0``  eq. 11 (see below)
    =====================  ==========================================  ===================

    with ``F = f_h,world + f_grav`` and ``Δθ = θ_o − θ_h``, ``s_g = x_o``. The paper pairs eq. 7
    with ``Δθ⁺`` and eq. 11 with ``ṡ_g⁺``; under ccopt's conventions (CCW angles, ``s_g = x_o``,
    ``τ`` CCW about the face centre) the physically consistent pairing is the one in the table:
    ``τ = l_h f_n`` puts the whole normal force at the hand's ``−e_t`` end, about which the object
    turns clockwise relative to the hand, and pushing the object towards ``+x`` needs
    ``F_x = −μ_g F_y``. The tests check the pairing against the simulator.

    Ground rows are naturally expressed in the world frame as ``a·f_h ≤ b`` (the estimator learns
    ``a`` and ``b`` without knowing the mass); :data:`cone_rows` rotates them into the hand frame.

Kinematics
    While flush, ``x_h(θ_o, s_h, s_g) = (r_o − s_h e_t − d e_n, θ_o)`` with ``r_o = (s_g, y_o)``
    (paper eq. 14). The admissible-motion vectors are its derivatives, in the hand frame:
    ``v_θ = (s_h, −d, 1)`` (the paper's ``[−d, s_h, 1]`` in ``(t, n, θ)`` order), ``v_h = (0, −1, 0)``
    (the paper's ``[−1, 0, 0]``) and ``v_g = (sin θ, cos θ, 0)`` (the world ``[1, 0, 0]``).
"""

from __future__ import annotations

from enum import IntEnum

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ccopt import geometry
from ccopt.casadi_eval import BufferedFunction


class Row(IntEnum):
    """Rows of the generalized friction cone, named after the motion each one blocks."""

    HAND_SLIDE_POS = 0
    HAND_SLIDE_NEG = 1
    HAND_PIVOT_POS = 2
    HAND_PIVOT_NEG = 3
    GROUND_SLIDE_POS = 4
    GROUND_SLIDE_NEG = 5


N_CONE_ROWS = len(Row)
HAND_ROWS = (Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG, Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG)
GROUND_ROWS = (Row.GROUND_SLIDE_POS, Row.GROUND_SLIDE_NEG)
_HAND_SLIDE_POS, _HAND_SLIDE_NEG = int(Row.HAND_SLIDE_POS), int(Row.HAND_SLIDE_NEG)  # plain ints index faster


def _sym(name: str, rows: int = 1, cols: int = 1) -> ca.SX:
    return ca.SX.sym(name, rows, cols)


def _build_hand_rows() -> ca.Function:
    mu_h, l_h = _sym("mu_h"), _sym("l_h")
    n_rows = ca.vertcat(
        ca.horzcat(-mu_h, -1, 0),
        ca.horzcat(-mu_h, 1, 0),
        ca.horzcat(-l_h, 0, -1),
        ca.horzcat(-l_h, 0, 1),
    )
    return ca.Function("hand_rows", [mu_h, l_h], [n_rows, ca.DM.zeros(4)], ["mu_h", "l_h"], ["N", "b"])


def _build_ground_rows_world() -> ca.Function:
    mu_g, f_grav = _sym("mu_g"), _sym("f_grav", 2)
    a = ca.vertcat(ca.horzcat(1, mu_g), ca.horzcat(-1, mu_g))
    b = ca.vertcat(-f_grav[0] - mu_g * f_grav[1], f_grav[0] - mu_g * f_grav[1])
    return ca.Function("ground_rows_world", [mu_g, f_grav], [a, b], ["mu_g", "f_grav"], ["A", "b"])


def _build_patch_torque_rows() -> ca.Function:
    l_h, s_h, face = _sym("l_h"), _sym("s_h"), _sym("face", 2)
    low = ca.fmax(-l_h, face[0] + s_h)
    high = ca.fmin(l_h, face[1] + s_h)
    rows = ca.vertcat(ca.horzcat(-high, 0, -1), ca.horzcat(low, 0, 1))
    return ca.Function("patch_torque_rows", [l_h, s_h, face], [rows], ["l_h", "s_h", "face"], ["N"])


hand_rows = _build_hand_rows()
"""``(μ_h, l_h) → (N (4×3), b (4))``: hand friction and torque rows in the hand frame, rows
``HAND_SLIDE_POS … HAND_PIVOT_NEG``."""

patch_torque_rows = _build_patch_torque_rows()
"""``(l_h, s_h, face (2)) → N (2×3)``: the torque rows ``HAND_PIVOT_POS, HAND_PIVOT_NEG`` (bounds 0)
of a contact patch that is the hand ``[−l_h, l_h]`` cut to the object's face, whose points lie at
``face = (u_low, u_high)`` from the ground contact's foot (m, :func:`ccopt.geometry.face_position`):
the centre of pressure ``c = −τ/f_n`` within ``[max(−l_h, u_low + s_h), min(l_h, u_high + s_h)]``.
An unbounded face (``±inf``) gives :data:`hand_rows`' torque rows; a hand past the face's end has
a patch shorter than the hand, and a hand off the face an empty one (no wrench satisfies both)."""


def patch_torque_margins(f_n: float, torque: float, low: float, high: float) -> tuple[float, float]:
    """The margins ``−N w`` (N·m) of the torque rows ``HAND_PIVOT_POS, HAND_PIVOT_NEG`` of the contact
    patch ``[low, high]`` (m, hand positions along ``e_t``) for the hand wrench's ``f_n`` (N) and ``τ``
    (N·m): :data:`patch_torque_rows` with the patch's ends given on the hand, in plain floats for a
    per-sample check. Both are positive while the centre of pressure lies inside the patch."""
    return high * f_n + torque, -low * f_n - torque


ground_rows_world = _build_ground_rows_world()
"""``(μ_g, f_grav (2)) → (A (2×2), b (2))``: the model's ground rows ``A f_h ≤ b`` on the world hand
force, rows ``GROUND_SLIDE_POS, GROUND_SLIDE_NEG``; ``f_grav`` is the object's weight (N, world)."""


def _build_cone_rows() -> ca.Function:
    theta_h, mu_h, l_h = _sym("theta_h"), _sym("mu_h"), _sym("l_h")
    ground_a, ground_b = _sym("ground_A", 2, 2), _sym("ground_b", 2)
    n_hand, b_hand = hand_rows(mu_h, l_h)
    n_ground = ca.horzcat(ground_a @ geometry.hand_frame(theta_h), ca.SX.zeros(2, 1))
    return ca.Function(
        "cone_rows",
        [theta_h, mu_h, l_h, ground_a, ground_b],
        [ca.vertcat(n_hand, n_ground), ca.vertcat(b_hand, ground_b)],
        ["theta_h", "mu_h", "l_h", "ground_A", "ground_b"],
        ["N", "b"],
    )


cone_rows = _build_cone_rows()
"""``(θ_h, μ_h, l_h, ground_A (2×2), ground_b (2)) → (N (6×3), b (6))``: the generalized friction
cone ``N w ≤ b`` in the hand frame, ground rows rotated from the world frame. Row order: :class:`Row`."""


def _build_complementarity_lhs() -> ca.Function:
    wrench, theta_h = _sym("w_h", 3), _sym("theta_h")
    mu_h, mu_g, l_h, f_grav = _sym("mu_h"), _sym("mu_g"), _sym("l_h"), _sym("f_grav", 2)
    ground_a, ground_b = ground_rows_world(mu_g, f_grav)
    n_rows, b = cone_rows(theta_h, mu_h, l_h, ground_a, ground_b)
    return ca.Function(
        "complementarity_lhs",
        [wrench, theta_h, mu_h, mu_g, l_h, f_grav],
        [b - n_rows @ wrench],
        ["w_h", "theta_h", "mu_h", "mu_g", "l_h", "f_grav"],
        ["lhs"],
    )


complementarity_lhs = _build_complementarity_lhs()
"""``(w_h, θ_h, μ_h, μ_g, l_h, f_grav) → lhs (6)``: the LHS of paper eqs. 5–8 and 11–12 (order
:class:`Row`); all ``≥ 0`` inside the cone, row ``k`` zero when the motion it blocks may happen."""


def _build_equilibrium_residual() -> ca.Function:
    hand_pose, wrench = _sym("hand_pose", 3), _sym("w_h", 3)
    f_ground, r_o, r_com, f_grav = _sym("f_ground", 2), _sym("r_o", 2), _sym("r_com", 2), _sym("f_grav", 2)
    f_hand = geometry.hand_frame(hand_pose[2]) @ wrench[:2]

    def moment(arm: ca.SX, force: ca.SX) -> ca.SX:
        return arm[0] * force[1] - arm[1] * force[0]

    force = f_hand + f_ground + f_grav
    torque = wrench[2] + moment(hand_pose[:2] - r_o, f_hand) + moment(r_com - r_o, f_grav)
    return ca.Function(
        "equilibrium_residual",
        [hand_pose, wrench, f_ground, r_o, r_com, f_grav],
        [ca.vertcat(force, torque)],
        ["hand_pose", "w_h", "f_ground", "r_o", "r_com", "f_grav"],
        ["net_wrench"],
    )


equilibrium_residual = _build_equilibrium_residual()
"""``(hand_pose, w_h, f_ground, r_o, r_com, f_grav) → (F_x, F_y, τ)``: the net wrench on the object
(paper eq. 1), torque about the ground contact ``r_o``; zero in static equilibrium. Forces in N,
world frame; ``w_h`` in the hand frame; the ground is a point contact at ``r_o``."""


def _build_kinematics() -> tuple[ca.Function, ca.Function]:
    theta_o, s_h, s_g, d, y_o = _sym("theta_o"), _sym("s_h"), _sym("s_g"), _sym("d"), _sym("y_o")
    hand_pose = geometry.hand_pose_from_contact(theta_o, s_h, d, ca.vertcat(s_g, y_o))
    forward = ca.Function(
        "hand_pose_kinematics",
        [theta_o, s_h, s_g, d, y_o],
        [hand_pose],
        ["theta_o", "s_h", "s_g", "d", "y_o"],
        ["hand_pose"],
    )
    to_hand = ca.diagcat(geometry.hand_frame(theta_o).T, 1)
    vectors = to_hand @ ca.jacobian(hand_pose, ca.vertcat(theta_o, s_h, s_g))
    motion = ca.Function(
        "motion_vectors",
        [theta_o, s_h, d],
        [ca.simplify(vectors)],
        ["theta_o", "s_h", "d"],
        ["V"],
    )
    return forward, motion


hand_pose_kinematics, motion_vectors = _build_kinematics()
"""``hand_pose_kinematics(θ_o, s_h, s_g, d, y_o) → x_h`` (world, paper eq. 14, flush hand).
``motion_vectors(θ_o, s_h, d) → V (3×3)``: columns ``v_θ, v_h, v_g``, the derivative of the hand
pose with respect to ``θ_o, s_h, s_g``, in the hand frame ``(n, t, θ)``."""

CONTACT_FUNCTIONS: tuple[ca.Function, ...] = (
    hand_rows,
    patch_torque_rows,
    ground_rows_world,
    cone_rows,
    complementarity_lhs,
    equilibrium_residual,
    hand_pose_kinematics,
    motion_vectors,
)
"""Every CasADi function of the contact model (for gradient checks and studies)."""


# --- NumPy wrappers -------------------------------------------------------------------------------

_numeric = {function.name(): BufferedFunction(function) for function in CONTACT_FUNCTIONS}


def weight(mass: float, gravity: float = geometry.GRAVITY) -> np.ndarray:
    """World gravity force on a body of ``mass`` kg: ``(0, −m g)`` N."""
    return np.array([0.0, -mass * gravity])


def friction_cone(
    theta_h: float, mu_h: float, l_h: float, ground_a: ArrayLike, ground_b: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Numeric :data:`cone_rows`: ``(N (6×3), b (6))`` in the hand frame."""
    return _numeric["cone_rows"](theta_h, mu_h, l_h, ground_a, ground_b)


def with_hand_friction(rows: ArrayLike, mu_h: float) -> np.ndarray:
    """Cone rows ``N`` (6×3, :class:`Row` order) with the hand friction rows taken at ``mu_h``
    (:data:`hand_rows`: ``−μ_h f_n ∓ f_t ≤ 0``)."""
    changed = np.array(rows, dtype=float)
    changed[_HAND_SLIDE_POS, 0] = changed[_HAND_SLIDE_NEG, 0] = -mu_h  # the controller's every tick
    return changed


def model_ground_rows(mu_g: float, mass: float) -> tuple[np.ndarray, np.ndarray]:
    """Numeric :data:`ground_rows_world` for a horizontal ground and an object of ``mass`` kg."""
    return _numeric["ground_rows_world"](mu_g, weight(mass))


def model_friction_cone(
    theta_h: float, mu_h: float, mu_g: float, l_h: float, mass: float
) -> tuple[np.ndarray, np.ndarray]:
    """The true cone of a known object: ``(N (6×3), b (6))`` in the hand frame."""
    ground_a, ground_b = model_ground_rows(mu_g, mass)
    return friction_cone(theta_h, mu_h, l_h, ground_a, ground_b)


def complementarity_margins(
    wrench: ArrayLike, theta_h: float, mu_h: float, mu_g: float, l_h: float, mass: float
) -> np.ndarray:
    """Numeric :data:`complementarity_lhs` for a horizontal ground; order :class:`Row`."""
    (lhs,) = _numeric["complementarity_lhs"](wrench, theta_h, mu_h, mu_g, l_h, weight(mass))
    return lhs


def admissible_motions(theta_o: float, s_h: float, d: float) -> np.ndarray:
    """Numeric :data:`motion_vectors`: columns ``v_θ, v_h, v_g`` in the hand frame."""
    return _numeric["motion_vectors"].call_scalars(theta_o, s_h, d)
