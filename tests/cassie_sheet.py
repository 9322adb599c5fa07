"""Cassie's reference numbers for the model tests: Agility Robotics' Cassie parameters as given in
the project's parameter sheet (``models/reference/cassie_parameters.json``, cross-checked by
``tests/test_model_cassie.py::test_constants_match_sheet``), and the composite-inertia helpers that
compare MuJoCo's and Pinocchio's whole-body mass properties."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amlip_qp.paths import MODELS_DIR

MODEL = MODELS_DIR / "cassie.xml"
#: The parameter sheet vendored in the repository (models/reference/, credits in NOTICE).
SHEET_PATH = Path(__file__).resolve().parents[1] / "models" / "reference" / "cassie_parameters.json"

SIDES = ("left", "right")
LEG = ("hip-roll", "hip-yaw", "hip-pitch", "knee", "shin", "tarsus", "foot")
JOINTS = [f"{s}-{j}" for s in SIDES for j in LEG]
MOTORS = [f"{s}-{j}" for s in SIDES for j in ("hip-roll", "hip-yaw", "hip-pitch", "knee", "foot")]
SITES = [f"{s}-{t}" for s in SIDES for t in ("toe", "heel", "contact")]
CONTACT_RADIUS = 0.02
COUPLING_REST = 0.226893  # knee + tarsus at heel-spring rest (13 deg = sum of the sheet's refs)

SHEET_TOTAL_MASS = 33.312
SHEET_PELVIS_MASS = 10.33
#: Per-leg body masses of the sheet (identical for both legs).
SHEET_LEG_MASSES = {
    "hip-roll": 1.82,
    "hip-yaw": 1.171,
    "hip-pitch": 5.52,
    "achilles-rod": 0.1567,
    "knee": 0.7578,
    "knee-spring": 0.186,
    "shin": 0.577,
    "tarsus": 0.782,
    "heel-spring": 0.126,
    "foot-crank": 0.1261,
    "plantar-rod": 0.1186,
    "foot": 0.1498,
}
#: Sheet bodies in the subtree of the knee joint.
SHEET_BELOW_KNEE = ("knee", "knee-spring", "shin", "tarsus", "heel-spring", "foot-crank", "plantar-rod", "foot")
SHEET_GEAR = {"hip-roll": 25.0, "hip-yaw": 25.0, "hip-pitch": 16.0, "knee": 16.0, "foot": 50.0}
SHEET_MOTOR_LIMIT = {"hip-roll": 4.5, "hip-yaw": 4.5, "hip-pitch": 12.2, "knee": 12.2, "foot": 0.9}
SHEET_RANGE = {
    "left-hip-roll": (-0.261799, 0.392699),
    "right-hip-roll": (-0.392699, 0.261799),
    "hip-yaw": (-0.392699, 0.392699),
    "hip-pitch": (-0.872665, 1.396263),
    "knee": (-2.86234, -0.645772),
    "shin": (-0.349066, 0.349066),
    "tarsus": (0.872665, 2.96706),
    "foot": (-2.443461, -0.523599),
}
#: The sheet's 35-element standing qpos (achilles-rod ball joints, heel spring, foot crank,
#: plantar rod included).
SHEET_STANDING_QPOS = [
    0,
    0,
    1.0059301,
    1,
    0,
    0,
    0,
    0.00449956,
    0,
    0.497301,
    0.97861,
    -0.0164104,
    0.0177766,
    -0.204298,
    -1.1997,
    0,
    1.42671,
    -2.25907e-06,
    -1.52439,
    1.50645,
    -1.59681,
    -0.00449956,
    0,
    0.497301,
    0.97874,
    0.0038687,
    -0.0151572,
    -0.204509,
    -1.1997,
    0,
    1.42671,
    0,
    -1.52439,
    1.50645,
    -1.59681,
]
#: Whole-robot CoM (world) and inertia about it (world axes) of the sheet's full 35-qpos tree
#: (all 31 bodies) at SHEET_STANDING_QPOS, computed by forward kinematics over the sheet.
SHEET_STANDING_COM = np.array([-1.755477085639e-02, 1.182208353924e-04, 8.773866413215e-01])
SHEET_STANDING_INERTIA = np.array(
    [
        [2.233339970233e00, -2.290130190445e-04, -3.876202677841e-01],
        [-2.290130190445e-04, 1.875362294852e00, -1.028483501288e-03],
        [-3.876202677841e-01, -1.028483501288e-03, 8.641190259791e-01],
    ]
)


def sheet_range(joint):
    side, short = joint.split("-", 1)
    return SHEET_RANGE.get(joint, SHEET_RANGE.get(short))


def sheet_qpos21():
    """The sheet's standing qpos reduced to the 21 entries of this model."""
    q = SHEET_STANDING_QPOS
    keep = [0, 1, 2, 3, 4, 5, 6]
    for start in (7, 21):
        # hip-roll, hip-yaw, hip-pitch, [achilles quat 4], knee, shin, tarsus, [heel, crank, plantar], foot
        keep += [start, start + 1, start + 2, start + 7, start + 8, start + 9, start + 13]
    return np.array([q[i] for i in keep], float)


def mj_to_pin(qpos):
    q = np.array(qpos, float).copy()
    q[3:7] = qpos[[4, 5, 6, 3]]  # wxyz -> xyzw
    return q


def composite(masses, coms, inertias):
    """Total mass, CoM and inertia about the CoM from per-body world quantities."""
    M = sum(masses)
    c = sum(m * x for m, x in zip(masses, coms)) / M
    I = np.zeros((3, 3))
    for m, x, Ii in zip(masses, coms, inertias):
        d = x - c
        I += Ii + m * (d @ d * np.eye(3) - np.outer(d, d))
    return M, c, I


def mj_composite(m, d):
    bodies = range(1, m.nbody)
    masses = [m.body_mass[b] for b in bodies]
    coms = [d.xipos[b].copy() for b in bodies]
    inertias = []
    for b in bodies:
        R = d.ximat[b].reshape(3, 3)
        inertias.append(R @ np.diag(m.body_inertia[b]) @ R.T)
    return composite(masses, coms, inertias)


def pin_composite(model, data):
    masses, coms, inertias = [], [], []
    for j in range(1, model.njoints):
        Y = model.inertias[j]
        oMi = data.oMi[j]
        masses.append(Y.mass)
        coms.append(oMi.act(Y.lever))
        inertias.append(oMi.rotation @ Y.inertia @ oMi.rotation.T)
    return composite(masses, coms, inertias)
