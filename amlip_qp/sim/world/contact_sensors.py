"""Foot-contact switches from MuJoCo contact sensors: the per-tick switches without per-contact Python calls.

:func:`contact_spec_edit` adds to a plant, per foot side, a MuJoCo contact
sensor ``amlip-contact-{side}`` matching the contacts between the foot's body
and the world body (``data="found force"``, ``reduce="none"``,
:data:`CONTACT_SLOTS` slots): MuJoCo fills it in each step's forward pass from
the same ``mjData.contact`` and ``efc_force`` as ``mj_contactForce`` (the same
numbers, tested), the matched contacts in their ``mjData.contact`` order.
:func:`sensor_switcher` reads the switches from ``sensordata`` with one NumPy
gather: a side's switch is on once the running sum of its contacts' normal
force magnitudes exceeds the threshold, as
:meth:`~amlip_qp.sim.world.plant.Plant.contact_switcher` (bit for bit: the same terms
in the same order); a side with more contacts than slots takes the general
path for that tick. Sensors change no trajectory.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

#: Contacts each foot's sensor reports (Cassie's feet have up to 2 each on flat ground).
CONTACT_SLOTS = 8
_FOUND, _FORCE = 1, 2  # mjtConDataField bits
_SLOT = 4  # numbers per slot: found, force (3, contact frame: normal first)


def contact_sensor_name(side: str) -> str:
    """The name of ``side``'s contact sensor."""
    return f"amlip-contact-{side}"


def contact_spec_edit(spec: mujoco.MjSpec, foot_bodies: dict[str, str]) -> None:
    """Add a contact sensor per side (side -> name of its foot's body) unless the model has one of that name.

    None with a MuJoCo older than its contact sensors (``mujoco>=3.2`` is allowed): the switches are
    then computed contact by contact.
    """
    if not hasattr(mujoco.mjtSensor, "mjSENS_CONTACT"):  # pragma: no cover - MuJoCo before 3.3
        return
    for side, body in foot_bodies.items():
        name = contact_sensor_name(side)
        if spec.sensor(name) is None:
            spec.add_sensor(
                name=name,
                type=mujoco.mjtSensor.mjSENS_CONTACT,
                objtype=mujoco.mjtObj.mjOBJ_BODY,
                objname=body,
                reftype=mujoco.mjtObj.mjOBJ_BODY,
                refname="world",
                intprm=[_FOUND | _FORCE, 0, CONTACT_SLOTS],  # data, reduce="none", num
            )


def sensor_switcher(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    foot_bodies: dict[str, int],
    threshold_N: float,
    general: Callable[[], dict[str, bool]],
) -> Callable[[], dict[str, bool]] | None:
    """``f()``: side -> switch from the contact sensors of :func:`contact_spec_edit`, or ``None`` without them.

    Args:
        model, data: The plant's (``data``'s ``sensordata`` is bound once).
        foot_bodies: Side -> plant body id of its foot (a sensor must match that body and the world).
        threshold_N: Normal force above which a switch is on, N.
        general: The switches computed contact by contact (a tick with more contacts than slots).

    ``None`` too when the sensors do not describe the contacts the step ends with (see
    :func:`contact_sensor_indices`).
    """
    gather = contact_sensor_indices(model, foot_bodies)
    if gather is None:
        return None
    sensordata, of_values = data.sensordata, list_switcher(tuple(foot_bodies), threshold_N, general)

    def switches() -> dict[str, bool]:
        return of_values(sensordata[gather].tolist())

    return switches


def contact_sensor_indices(model: mujoco.MjModel, foot_bodies: dict[str, int]) -> np.ndarray | None:
    """The ``sensordata`` indices that :func:`list_switcher` reads (per side: the count of contacts
    found, then each slot's normal force), or ``None`` without the sensors of :func:`contact_spec_edit`.

    ``None`` too when the sensors do not describe the contacts the step ends with: with the
    RK4 integrator (its later stages recompute the contacts but not the sensors) or with the
    sensors disabled (``<flag sensor="disable"/>``).
    """
    opt = model.opt
    if opt.integrator == mujoco.mjtIntegrator.mjINT_RK4 or opt.disableflags & mujoco.mjtDisableBit.mjDSBL_SENSOR:
        return None
    idx: list[int] = []
    for side, body in foot_bodies.items():
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, contact_sensor_name(side))
        if sid < 0 or not (
            model.sensor_type[sid] == mujoco.mjtSensor.mjSENS_CONTACT
            and model.sensor_objtype[sid] == mujoco.mjtObj.mjOBJ_BODY
            and model.sensor_objid[sid] == body
            and model.sensor_reftype[sid] == mujoco.mjtObj.mjOBJ_BODY
            and model.sensor_refid[sid] == 0
            and model.sensor_intprm[sid].tolist() == [_FOUND | _FORCE, 0, CONTACT_SLOTS]
        ):
            return None
        adr = int(model.sensor_adr[sid])
        idx += [adr] + [adr + _SLOT * i + 1 for i in range(CONTACT_SLOTS)]  # found, then each slot's normal
    return np.array(idx, dtype=np.intp)


def list_switcher(
    sides: tuple[str, ...], threshold_N: float, general: Callable[[], dict[str, bool]]
) -> Callable[[list[float]], dict[str, bool]]:
    """``f(values)``: side -> switch, ``values`` starting with ``sensordata[contact_sensor_indices(...)]``.

    A side's switch is on once the running sum of its contacts' normal force magnitudes
    exceeds ``threshold_N``; a side with more contacts than slots takes ``general()``.
    """
    none_on, n = 0.0 > threshold_N, CONTACT_SLOTS
    layout = tuple((side, i * (n + 1)) for i, side in enumerate(sides))  # each side's count of contacts found

    def switches(values: list[float]) -> dict[str, bool]:
        on: dict[str, bool] = {}
        for side, j in layout:
            found = values[j]
            if found > n:
                return general()  # the slots hold only the first contacts
            switch = none_on  # no contact: a zero sum
            if found:
                total = 0.0
                for f in values[j + 1 : j + 1 + int(found)]:
                    total += abs(f)
                    if total > threshold_N:  # a rounded sum of magnitudes never decreases: known
                        switch = True
                        break
            on[side] = switch
        return on

    return switches
