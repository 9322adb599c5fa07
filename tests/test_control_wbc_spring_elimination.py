"""Rigid springs: their constraint forces eliminated exactly, the torque map, and the clear errors."""

import casadi as ca
import numpy as np
import pytest

from amlip_qp.control.wbc.builder import WholeBodyQP
from amlip_qp.control.wbc.inputs import SymbolicInputs
from amlip_qp.control.wbc.layout import VariableLayout
from amlip_qp.control.wbc.spring_elimination import LegSprings, SpringElimination, springs_per_leg
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from robot_states import tuned_config
from wbc_cases import build_and_solve, kin_at, target_for

CASSIE_CONFIG = tuned_config("cassie", "qp")


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


@pytest.mark.parametrize("mode", ["all", "swing", "none"])
@pytest.mark.parametrize("stance", ["left", "right"])
def test_row_map_gives_the_dynamics_rows_torques_and_spring_forces(cassie, mode, stance):
    """For any x, R [D | hp] must equal the full dynamics residual
    D x + hp - G^T lambda on the kept unactuated rows, the torques on the
    actuated rows, and lambda itself, with lambda the one force that zeroes
    the held springs' passive rows."""
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(rigid_springs=mode))
    kin = kin_at(cassie, seed=3)
    builder.build(kin, target_for(kin, stance))
    L, dyn = builder.layout, builder.dynamics
    el = dyn.elimination
    x = np.random.default_rng(0).normal(0.0, 5.0, L.n)
    D = np.hstack([kin.mass_matrix(), -builder.inputs.Jf.T])
    full = D @ x + kin.nonlinear_effects() - kin.passive_forces()
    rs = el.rows(stance)
    held = ([stance] if L.n_rigid_st else []) + ([("right" if stance == "left" else "left")] if L.n_rigid_sw else [])
    G = np.vstack([el.leg_springs[s].G for s in held]) if held else np.zeros((0, cassie.nv))
    assert np.array_equal(rs.G, G) and np.array_equal(dyn.G, G)
    P = [i for i in cassie.passive_v_idx if np.any(G[:, i] != 0.0)]
    lam = np.linalg.solve(G[:, P].T, full[P]) if held else np.zeros(0)
    residual = full - G.T @ lam
    assert np.max(np.abs(residual[P]), initial=0.0) < 1e-9 * np.max(np.abs(full))
    kept = [i for i in range(cassie.nv) if i not in P and i not in el.act_v]
    expected = np.concatenate([residual[kept], residual[el.act_v], lam])
    got = dyn.RD @ x + dyn.Rhp
    assert got.shape == expected.shape == (el.n_dyn + el.act_v.size + L.n_lambda,)
    assert np.allclose(got, expected, rtol=1e-10, atol=1e-8 * np.max(np.abs(expected)))
    assert np.array_equal(dyn.torques(x), dyn.T @ x + dyn.tau0)
    assert np.allclose(dyn.rigid_forces(x), lam, rtol=1e-10, atol=1e-8)


def test_symbolic_terms_equal_the_numeric_ones(cassie):
    builder = WholeBodyQP(cassie)
    kin = kin_at(cassie, seed=4)
    builder.build(kin, target_for(kin, "right"))
    inp, L = builder.inputs, builder.layout
    sym = SymbolicInputs.create("right", cassie.nq, L, builder.output_task.size)
    terms = builder.dynamics.symbolic(sym)
    fn = ca.Function("f", [sym.arguments[0], sym.hp, sym.JfT], [terms.RD, terms.Rhp, terms.T, terms.tau0])
    upper = np.triu(inp.mass_upper) + 1e9 * np.tril(np.ones_like(inp.mass_upper), -1)  # only the upper is read
    RD, Rhp, T, tau0 = (np.asarray(v) for v in fn(upper, inp.hp, inp.Jf.T))
    dyn = builder.dynamics
    assert np.allclose(RD, dyn.RD, rtol=1e-12, atol=1e-9) and np.allclose(Rhp.ravel(), dyn.Rhp, rtol=1e-12, atol=1e-9)
    assert np.allclose(T, dyn.T, rtol=1e-12, atol=1e-9) and np.allclose(tau0.ravel(), dyn.tau0, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("mode, n_lambda", [("all", 4), ("swing", 2), ("none", 0)])
def test_eliminated_spring_forces_close_every_dynamics_row_of_a_solution(cassie, mode, n_lambda):
    """Recovered from the passive rows, the rigid springs' forces must close the
    full dynamics (all nv rows) of a solved problem and hold the springs' rate
    rows, whichever legs are held rigid."""
    builder = WholeBodyQP(cassie, CASSIE_CONFIG.with_(rigid_springs=mode))
    for stance in ("left", "right"):
        # At the standing springs (random spring deflections with free springs
        # can need more than the motors' torque: infeasible by the torque rows).
        kin = kin_at(cassie, seed=11, scale=0.0)
        problem, x = build_and_solve(builder, kin, target_for(kin, stance, phase=0.4, offset=0.01))
        assert problem.n == cassie.nv + 12
        assert problem.n_eq == 6 + (4 - n_lambda) + 5 + n_lambda
        lam = builder.rigid_forces(x)
        assert lam.shape == (n_lambda,) and np.all(np.isfinite(lam))
        vdot = x[problem.variables["vdot"]]
        S_T_tau = np.zeros(cassie.nv)
        S_T_tau[cassie.actuated.pin_v_idx] = builder.torques(x)
        lhs = kin.mass_matrix() @ vdot + kin.nonlinear_effects() - kin.passive_forces()
        rhs = S_T_tau + builder.generalized_contact_force(x)
        assert np.max(np.abs(lhs - rhs)) < 1e-6 * max(1.0, np.max(np.abs(lhs)))
        if n_lambda:
            assert np.max(np.abs(lam)) > 1e-3  # held springs carry load


def _elimination(cassie, leg_springs):
    L = VariableLayout.for_robot(cassie, springs_per_leg(leg_springs), springs_per_leg(leg_springs))
    return SpringElimination(cassie, L, CASSIE_CONFIG, leg_springs)


def test_springs_that_cannot_be_eliminated_are_a_clear_error(cassie):
    """A held leg needs one passive joint per held spring (its rows give the
    springs' constraint forces); otherwise the message says what to change."""
    springs = LegSprings.of_robot(cassie)
    assert springs_per_leg(springs) == 2 and _elimination(cassie, springs).n_dyn == 6
    left = springs["left"]
    # A third spring on each leg with only two passive joints (shin, tarsus).
    three = {s: LegSprings(np.vstack([v.G, v.G[:1]]), np.vstack([v.Gq, v.Gq[:1]]), np.r_[v.rest, v.rest[:1]])
             for s, v in springs.items()}  # fmt: skip
    with pytest.raises(InputError, match="rigid_springs='none'"):
        _elimination(cassie, three)
    # Two springs on the same pair of passive joints: square but singular.
    shin, tarsus = int(np.flatnonzero(left.G[1])[0]), int(np.flatnonzero(left.G[0])[-1])
    both = np.zeros_like(left.G[:1])
    both[0, [shin, tarsus]] = 1.0
    singular = dict(springs, left=LegSprings(np.vstack([both, both]), left.Gq, left.rest))
    with pytest.raises(InputError, match="singular"):
        _elimination(cassie, singular)
    with pytest.raises(InputError, match="same number"):
        springs_per_leg(dict(springs, left=LegSprings(left.G[:1], left.Gq[:1], left.rest[:1])))
    # The builder passes its springs on: the same errors there.
    with pytest.raises(InputError, match="singular"):
        WholeBodyQP(cassie, leg_springs=singular)
    assert WholeBodyQP(cassie, CASSIE_CONFIG.with_(rigid_springs="none"), leg_springs=singular).layout.n_lambda == 0
