"""Plant modifiers: a model mismatch between the MuJoCo plant and the controller's model.

:class:`PlantModifiers` holds the mismatch of one run (the CLI flags
``--plant-mass-scale``, ``--payload KG[@X,Y,Z]``, ``--plant-spring-scale``,
``--friction MU``, ``--limb-collisions`` and ``--actuator-delay TICKS``). All but the delay are edits
of the plant's ``mujoco.MjSpec`` applied before it is compiled
(:meth:`PlantModifiers.spec_edits`); the delay is an
:class:`~amlip_qp.sim.world.actuator_delay.ActuatorDelay` the harness puts
between the controller and ``data.ctrl``. The controller's own
(Pinocchio) model is never touched: that is the point of the mismatch.

The defaults change nothing: ``PlantModifiers().spec_edits(...)`` is empty and
an ``ActuatorDelay(0, nu)`` hands back the very array it is given.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError, MJCFError

#: Type of one edit: it changes a plant's spec in place, before compilation.
SpecEdit = Callable[[mujoco.MjSpec], None]

#: Bounds of the modifiers: the range in which the plant is still a robot MuJoCo simulates faithfully
#: (beyond them the value is a typo or a model that diverges). Measured with
#: ``amlip-qp walk --duration 1 --plant P --plant-mass-scale S`` (and ``--plant-spring-scale S``) for the
#: plants cassie and cassie-closed-chain, MuJoCo 4.0.1:
#:
#: - mass scale ``[0.1, 10]``: at 0.01 the closed-chain plant diverges (mean base speed 32 m/s over
#:   its 0.13 s; 418 m/s at 0.001): the bodies of its loops (rods, cranks, spring links of 0.12-0.19 kg)
#:   weigh grams there, while the springs and the rotor inertias keep their values. From 0.1 to 10 both
#:   plants walk, or fall at walking speeds (a mismatch the controller does not survive is a result,
#:   not an error); unactuated from the stand keyframe, they fall without MuJoCo's instability warning
#:   at the bounds and with it past them (``tests/test_sim_plant_modifiers.py``).
#: - spring scale ``[0, 10]``: 0 removes the springs (a limp plant); at 10 Cassie's knee and heel
#:   springs (1500 and 1250 N m/rad) deflect ten times less under the body weight, near rigid.
#:   MuJoCo's explicit springs diverge at the 0.5 ms step from 200 x on the closed chain (it falls at
#:   0.00 s with a mean base speed of 680 m/s) and from 500 x on cassie.xml; 10 keeps a factor 20.
#: - friction ``[1e-5, 10]``: MuJoCo raises any coefficient below ``mjMINMU`` = 1e-5 to it; 10 is an
#:   order of magnitude above rubber on dry concrete (about 1).
MIN_MASS_SCALE = 0.1
MAX_MASS_SCALE = 10.0
MAX_SPRING_SCALE = 10.0
MAX_PAYLOAD_KG = 100.0
MAX_PAYLOAD_OFFSET_M = 1.0
MIN_FRICTION = float(mujoco.mjMINMU)
MAX_FRICTION = 10.0
MAX_DELAY_TICKS = 100

#: Edge lengths (x, y, z) of the payload box, m: about a laptop-bag-sized load.
PAYLOAD_BOX_M = (0.2, 0.15, 0.1)
#: Name of the body :class:`PayloadEdit` adds.
PAYLOAD_BODY = "amlip-payload"


def _finite(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(float(x))


@dataclass(frozen=True)
class PlantModifiers:
    """How the plant differs from the model it was loaded from.

    Attributes:
        mass_scale: Factor on the mass and the rotational inertia of every body
            (their CoMs stay where they are), in [0.1, 10]. Rotor inertias
            (joint armature) are the motors', not the bodies', and stay.
        payload_kg: Mass of a box welded to the base body, kg, in [0, 100];
            0 adds nothing. The box is 0.2 x 0.15 x 0.1 m (x, y, z in the base
            frame, :data:`PAYLOAD_BOX_M`), uniform, and collides with nothing.
        payload_pos_m: Centre of the payload box in the base-body frame, m
            (each coordinate within 1 m); only with ``payload_kg > 0``.
        spring_scale: Factor on every joint and tendon stiffness (Cassie's
            knee/shin and heel springs, ``cassie.xml``'s achilles tendons,
            whatever springs the plant has), in [0, 10] (0 removes the springs).
        friction: The sliding friction coefficient of every foot-floor contact
            (sets the floor's and every geom's that can touch it; see
            :class:`FrictionEdit`), in [1e-5, 10]; ``None`` keeps the model's.
        limb_collisions: The limbs collide with each other (:class:`LimbCollisionEdit`): the legs
            cannot pass through each other; ``False`` keeps the model's collisions.
        actuator_delay_ticks: Whole controller ticks between the controller's
            command and the plant's actuators, in [0, 100] (see
            :class:`~amlip_qp.sim.world.actuator_delay.ActuatorDelay`).

    Raises:
        InputError: A nonsensical value (one line saying what to give).
    """

    mass_scale: float = 1.0
    payload_kg: float = 0.0
    payload_pos_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    spring_scale: float = 1.0
    friction: float | None = None
    limb_collisions: bool = False
    actuator_delay_ticks: int = 0

    def __post_init__(self):
        s = self.mass_scale
        if not _finite(s) or not MIN_MASS_SCALE <= s <= MAX_MASS_SCALE:
            raise InputError(
                f"plant mass scale (--plant-mass-scale) must be a number in [{MIN_MASS_SCALE:g}, {MAX_MASS_SCALE:g}], "
                f"got {s!r}; e.g. 0.8 or 1.2"
            )
        kg = self.payload_kg
        if not _finite(kg) or not 0.0 <= kg <= MAX_PAYLOAD_KG:
            raise InputError(
                f"payload (--payload) must be a mass in [0, {MAX_PAYLOAD_KG:g}] kg, got {kg!r}; "
                "e.g. --payload 5@-0.1,0,0"
            )
        pos = self.payload_pos_m
        if (
            isinstance(pos, str)
            or not isinstance(pos, Sequence)
            or len(pos) != 3
            or not all(_finite(x) and abs(x) <= MAX_PAYLOAD_OFFSET_M for x in pos)
        ):
            raise InputError(
                "payload position (--payload KG@X,Y,Z) must be 3 numbers within "
                f"{MAX_PAYLOAD_OFFSET_M:g} m of the base body, got {pos!r}; e.g. --payload 5@-0.1,0,0"
            )
        object.__setattr__(self, "payload_pos_m", tuple(float(x) for x in pos))
        if kg == 0.0 and any(self.payload_pos_m):
            raise InputError(
                f"payload position {self.payload_pos_m} given with a 0 kg payload; give a mass > 0 kg or no position"
            )
        k = self.spring_scale
        if not _finite(k) or not 0.0 <= k <= MAX_SPRING_SCALE:
            raise InputError(
                f"plant spring scale (--plant-spring-scale) must be a number in [0, {MAX_SPRING_SCALE:g}], "
                f"got {k!r}; e.g. 0.8"
            )
        mu = self.friction
        if mu is not None and (not _finite(mu) or not MIN_FRICTION <= mu <= MAX_FRICTION):
            raise InputError(
                f"friction (--friction) must be a coefficient in [{MIN_FRICTION:g}, {MAX_FRICTION:g}], got {mu!r}; "
                "e.g. 0.5"
            )
        if not isinstance(self.limb_collisions, bool):
            raise InputError(f"limb collisions (--limb-collisions) must be true or false, got {self.limb_collisions!r}")
        n = self.actuator_delay_ticks
        if not isinstance(n, numbers.Integral) or isinstance(n, bool) or not 0 <= n <= MAX_DELAY_TICKS:
            raise InputError(
                f"actuator delay (--actuator-delay) must be a whole number of ticks in [0, {MAX_DELAY_TICKS}], "
                f"got {n!r}; e.g. 1"
            )
        object.__setattr__(self, "actuator_delay_ticks", int(n))

    def spec_edits(self, base_body: str) -> list[SpecEdit]:
        """The spec edits of these modifiers (all but the delay), in the order to apply them.

        The mass scale comes before the payload, so the payload keeps its
        mass. The defaults give no edit.

        Args:
            base_body: Name of the plant's base body (it carries the payload).
        """
        edits: list[SpecEdit] = []
        if self.mass_scale != 1.0:
            edits.append(MassScaleEdit(float(self.mass_scale)))
        if self.payload_kg > 0.0:
            edits.append(PayloadEdit(base_body, float(self.payload_kg), self.payload_pos_m))
        if self.spring_scale != 1.0:
            edits.append(SpringScaleEdit(float(self.spring_scale)))
        if self.friction is not None:
            edits.append(FrictionEdit(float(self.friction)))
        if self.limb_collisions:
            edits.append(LimbCollisionEdit(base_body))
        return edits

    def describe(self) -> dict:
        """The fields that differ from the defaults, JSON-ready, for a run summary."""
        out: dict = {}
        if self.mass_scale != 1.0:
            out["mass_scale"] = float(self.mass_scale)
        if self.payload_kg > 0.0:
            out["payload_kg"] = float(self.payload_kg)
            out["payload_pos_m"] = list(self.payload_pos_m)
        if self.spring_scale != 1.0:
            out["spring_scale"] = float(self.spring_scale)
        if self.friction is not None:
            out["friction"] = float(self.friction)
        if self.limb_collisions:
            out["limb_collisions"] = True
        if self.actuator_delay_ticks:
            out["actuator_delay_ticks"] = self.actuator_delay_ticks
        return out


def parse_payload(text: str) -> tuple[float, tuple[float, float, float]]:
    """Parse the CLI's ``KG[@X,Y,Z]``: a mass in kg, optionally at (x, y, z) m in the base frame.

    ``"5"`` is 5 kg at the base body's origin; ``"5@-0.1,0,0"`` is 5 kg 10 cm
    behind it. Returns ``(kg, (x, y, z))``, checked as :class:`PlantModifiers` checks them.

    Raises:
        InputError: Malformed text or a nonsensical value (one line).
    """
    kg_text, sep, pos_text = str(text).strip().partition("@")
    try:
        kg = float(kg_text)
        pos = tuple(float(x) for x in pos_text.split(",")) if sep else (0.0, 0.0, 0.0)
    except ValueError:
        raise InputError(
            f"--payload takes KG or KG@X,Y,Z (kg, m in the base frame), got {text!r}; e.g. 5@-0.1,0,0"
        ) from None
    if len(pos) != 3:
        raise InputError(f"--payload position needs 3 coordinates X,Y,Z (m), got {pos_text!r}; e.g. 5@-0.1,0,0")
    mods = PlantModifiers(payload_kg=kg, payload_pos_m=pos)
    return mods.payload_kg, mods.payload_pos_m


def is_static_body(body: mujoco.MjsBody) -> bool:
    """Whether a body is the world or welded to it (no joint up to the world, not mocap)."""
    while body.name != "world":
        if body.joints or body.mocap:
            return False
        body = body.parent
    return True


@dataclass(frozen=True)
class MassScaleEdit:
    """Scale the mass and inertia of every body by ``scale`` (CoMs unchanged).

    A body's mass comes from its ``<inertial>`` or from its geoms, as the
    compiler's ``inertiafromgeom`` decides, and the edit scales that source:
    the inertial's mass, diagonal and full inertia, or the geoms' mass (when
    given) or density. The compiler's ``boundmass``, ``boundinertia`` and
    ``settotalmass`` scale too, so they keep their meaning.
    """

    scale: float

    def __call__(self, spec: mujoco.MjSpec) -> None:
        s = self.scale
        from_geoms = spec.compiler.inertiafromgeom
        for body in spec.bodies:
            if body.name == "world":
                continue
            if from_geoms == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE or (
                from_geoms == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO and not body.explicitinertial
            ):
                for geom in body.geoms:
                    if math.isnan(geom.mass):
                        geom.density = s * geom.density
                    else:
                        geom.mass = s * geom.mass
            else:
                body.mass = s * body.mass
                body.inertia = s * np.asarray(body.inertia)
                if not math.isnan(body.fullinertia[0]):
                    body.fullinertia = s * np.asarray(body.fullinertia)
        for attr in ("boundmass", "boundinertia", "settotalmass"):
            value = getattr(spec.compiler, attr)
            if value > 0:
                setattr(spec.compiler, attr, s * value)


@dataclass(frozen=True)
class PayloadEdit:
    """Weld a uniform box of ``mass_kg`` to ``base_body``, centred at ``pos_m`` (base frame, m).

    The box is :data:`PAYLOAD_BOX_M` in size, aligned with the base frame,
    adds no joint (the state layout and keyframes stay valid) and collides
    with nothing. Its mass and inertia are given both as the body's inertial
    and as its geom's mass, so it weighs ``mass_kg`` whatever the plant's
    ``inertiafromgeom``.
    """

    base_body: str
    mass_kg: float
    pos_m: tuple[float, float, float]

    def __call__(self, spec: mujoco.MjSpec) -> None:
        base = spec.body(self.base_body)
        if base is None:
            raise MJCFError(
                f"the plant has no body {self.base_body!r} to carry the payload; give the plant's base body name"
            )
        if spec.compiler.settotalmass > 0:
            raise MJCFError(
                "the plant's compiler sets settotalmass, which would rescale the payload; remove it to use --payload"
            )
        lx, ly, lz = PAYLOAD_BOX_M
        m = self.mass_kg
        body = base.add_body(
            name=PAYLOAD_BODY,
            pos=list(self.pos_m),
            mass=m,
            ipos=[0.0, 0.0, 0.0],
            inertia=[m * (ly**2 + lz**2) / 12.0, m * (lx**2 + lz**2) / 12.0, m * (lx**2 + ly**2) / 12.0],
            explicitinertial=True,
        )
        body.add_geom(
            name=PAYLOAD_BODY,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[lx / 2.0, ly / 2.0, lz / 2.0],
            mass=m,
            contype=0,
            conaffinity=0,
            group=1,
            rgba=[0.8, 0.3, 0.3, 1.0],
        )


@dataclass(frozen=True)
class SpringScaleEdit:
    """Scale every joint and tendon stiffness (all polynomial coefficients) by ``scale``.

    The spring rest positions (``springref``, ``springlength``) stay.
    """

    scale: float

    def __call__(self, spec: mujoco.MjSpec) -> None:
        s = self.scale
        for joint in spec.joints:
            if all(x > 0 for x in joint.springdamper):
                raise MJCFError(
                    f"plant joint {joint.name!r} sets its spring by springdamper, which --plant-spring-scale "
                    "cannot scale; give it a stiffness instead"
                )
            joint.stiffness = s * np.asarray(joint.stiffness)
        for tendon in spec.tendons:
            tendon.stiffness = s * np.asarray(tendon.stiffness)


@dataclass(frozen=True)
class FrictionEdit:
    """Make the sliding friction of every contact with the ground exactly ``mu``.

    The ground is every geom of the world body or of a body welded to it.
    MuJoCo gives a contact the friction of the geom of higher ``priority``,
    else the element-wise maximum of the two geoms' (MuJoCo's modeling guide,
    "Contact parameters"); setting the sliding coefficient of the ground and of
    every geom that can collide with it (``contype``/``conaffinity``) makes it
    ``mu`` under either rule. Explicit contact pairs with the ground get ``mu``
    on both tangent axes, and so does the global override when the plant
    enables it. Torsional and rolling coefficients stay.
    """

    mu: float

    def __call__(self, spec: mujoco.MjSpec) -> None:
        ground = [g for g in spec.geoms if is_static_body(g.parent)]
        if not ground:
            raise MJCFError("the plant has no geom on the world body (a floor) to set --friction on; add a floor")
        for geom in spec.geoms:
            if geom in ground or any((geom.contype & f.conaffinity) or (f.contype & geom.conaffinity) for f in ground):
                geom.friction = [self.mu, geom.friction[1], geom.friction[2]]
        ground_names = {g.name for g in ground if g.name}
        for pair in spec.pairs:
            if pair.geomname1 in ground_names or pair.geomname2 in ground_names:
                pair.friction = [self.mu, self.mu, *pair.friction[2:]]
        if spec.option.enableflags & mujoco.mjtEnableBit.mjENBL_OVERRIDE:
            spec.option.o_friction = [self.mu, self.mu, *spec.option.o_friction[2:]]


@dataclass(frozen=True)
class LimbCollisionEdit:
    """Make the limbs collide with each other: each subtree of bodies under the base body (a biped's
    two legs; a humanoid's legs and its torso with the arms) collides with every other one.

    Every primitive geom of a subtree (mesh geoms stay as they are) gets the subtree's own collision
    bit in ``contype`` and the other subtrees' bits in ``conaffinity``; MuJoCo makes a contact where
    ``contype`` of one geom and ``conaffinity`` of the other share a bit. Bit 0, the ground's, is left
    alone, so nothing collides with the ground that did not, and the geoms of one subtree do not
    collide with each other. Cassie's leg capsules are visual geoms that collide with nothing
    (``contype`` = ``conaffinity`` = 0): with this edit the legs cannot pass through each other.
    The new contacts take the geoms' own parameters (MuJoCo's defaults for Cassie's capsules).
    """

    base_body: str

    def __call__(self, spec: mujoco.MjSpec) -> None:
        base = spec.body(self.base_body)
        if base is None:
            raise MJCFError(f"the plant has no body {self.base_body!r} to find the limbs under")
        limbs = list(base.bodies)
        if len(limbs) < 2:
            raise MJCFError(f"--limb-collisions: the base body {self.base_body!r} carries {len(limbs)} limb(s), not 2")
        if len(limbs) > 30:
            raise MJCFError(f"--limb-collisions: {len(limbs)} limbs under {self.base_body!r}; at most 30 have bits")
        bits = [1 << (k + 1) for k in range(len(limbs))]
        everyone = sum(bits)
        for limb, bit in zip(limbs, bits):
            for geom in limb.find_all(mujoco.mjtObj.mjOBJ_GEOM):
                if geom.type != mujoco.mjtGeom.mjGEOM_MESH:
                    geom.contype = int(geom.contype) | bit
                    geom.conaffinity = int(geom.conaffinity) | (everyone & ~bit)
