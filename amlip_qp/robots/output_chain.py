"""Chain scalars: scalar functions of the state with their value, rate, Jacobian coefficients and drift.

The scalar chain rule of the output map (:mod:`amlip_qp.robots.outputs`) on plain Python
floats packed in tuples: no per-scalar objects, the floating-point operations of the
plain per-row formulas (so the output map's results are the same to the last bit).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

# A "chain scalar" is a tuple ``(val, rate, c0, c1, c2, jdv)``: a scalar
# function of the state with its value, its time derivative ``J v``, its
# Jacobian as three coefficients ``(c0, c1, c2)`` on the rows of a 3 x nv basis
# Jacobian chosen by the caller (the base's angular Jacobian for rotation
# entries, the toe-minus-heel point Jacobian for the foot pitch) and its drift
# ``Jdot v``. Units follow the quantity (rad or m; per s; per s^2).


def atan2_chain(a: tuple, b: tuple) -> tuple:
    """``atan2(a, b)`` of two chain scalars, with the chain rule.

    ``y' = (b a' - a b') / r^2`` and
    ``y'' = (b a'' - a b'') / r^2 - 2 (b a' - a b') (a a' + b b') / r^4``.
    """
    av, ar, a0, a1, a2, aj = a
    bv, br, b0, b1, b2, bj = b
    r2 = av * av + bv * bv
    num = bv * ar - av * br
    ka, kb = bv / r2, -av / r2
    jdv = (bv * aj - av * bj) / r2 - 2.0 * num * (av * ar + bv * br) / (r2 * r2)
    return (math.atan2(av, bv), num / r2, ka * a0 + kb * b0, ka * a1 + kb * b1, ka * a2 + kb * b2, jdv)


def hypot_chain(a: tuple, b: tuple) -> tuple:
    """``sqrt(a^2 + b^2)`` of two chain scalars, with the chain rule.

    ``rho' = (a a' + b b') / rho`` and
    ``rho'' = (a a'' + b b'' + a'^2 + b'^2) / rho - (a a' + b b')^2 / rho^3``.
    """
    av, ar, a0, a1, a2, aj = a
    bv, br, b0, b1, b2, bj = b
    rho = math.hypot(av, bv)
    dot = av * ar + bv * br
    ka, kb = av / rho, bv / rho
    jdv = (av * aj + bv * bj + ar * ar + br * br) / rho - dot * dot / rho**3
    return (rho, dot / rho, ka * a0 + kb * b0, ka * a1 + kb * b1, ka * a2 + kb * b2, jdv)


def neg_chain(a: tuple) -> tuple:
    """``-a`` of a chain scalar."""
    return (-a[0], -a[1], -a[2], -a[3], -a[4], -a[5])


def rotation_column(R: list, j: int, w: Sequence[float], alpha: Sequence[float]) -> tuple:
    """Entries ``(R_0j, R_1j, R_2j)`` of a body's world rotation ``R`` (nested lists) as chain scalars.

    The basis is the body's angular Jacobian. With ``w`` the world angular
    velocity (rad/s) and ``alpha`` the angular acceleration drift (rad/s^2),
    the column ``r = r_j`` moves as ``dr = w x r``, its second-derivative drift
    is ``alpha x r + w x dr``, and ``d/dt R_ij = (r x e_i) . w`` gives the
    coefficients ``r x e_i``.
    """
    w0, w1, w2 = w
    a0, a1, a2 = alpha
    r0, r1, r2 = R[0][j], R[1][j], R[2][j]
    dr0, dr1, dr2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0
    return (
        (r0, dr0, 0.0, r2, -r1, (a1 * r2 - a2 * r1) + (w1 * dr2 - w2 * dr1)),
        (r1, dr1, -r2, 0.0, r0, (a2 * r0 - a0 * r2) + (w2 * dr0 - w0 * dr2)),
        (r2, dr2, r1, -r0, 0.0, (a0 * r1 - a1 * r0) + (w0 * dr1 - w1 * dr0)),
    )


def rotation_entry_z(R: list, j: int, w: Sequence[float], alpha: Sequence[float]) -> tuple:
    """The entry ``R_2j`` alone of :func:`rotation_column` (the same arithmetic, fewer terms)."""
    w0, w1, w2 = w
    a0, a1, _ = alpha
    r0, r1, r2 = R[0][j], R[1][j], R[2][j]
    dr0, dr1 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2
    return (r2, w0 * r1 - w1 * r0, r1, -r0, 0.0, (a0 * r1 - a1 * r0) + (w0 * dr1 - w1 * dr0))
