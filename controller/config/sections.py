"""The sections of :class:`controller.config.ControllerConfig`: every tuning constant of the
balance controller and the servo tracking, each with its unit in its name or its comment,
and the measurement or reason that chose its value beside it (moved here from the modules
that read them, which now take them from the configuration they are given)."""

from __future__ import annotations

from dataclasses import dataclass

from upm.motion.dropouts import DROPOUT_JUMP_DEG

#: What a mode may leave out of the plan's support (:attr:`Mode.swing_contacts_excluded`).
SWING_CONTACTS = ("none", "swing toes", "foot")


@dataclass(frozen=True)
class StepConfig:
    """The physics step (the balance controller and the servo tracking)."""

    #: The longest physics step used, seconds (the model's own timestep): the step is the
    #: largest no longer than this that divides the frame period (120 fps: 5 steps of
    #: 1.667 ms per frame), so every frame falls on a step.
    max_step_s: float = 0.002


@dataclass(frozen=True)
class DropoutsConfig:
    """Marker dropouts in the reference (:mod:`controller.dropouts`): bones whose angles
    read exactly zero for a few frames between frames far from zero."""

    #: A bone's run of zeros is a dropout when the frames around it are at least this far
    #: from zero, degrees (the motion layer's own threshold,
    #: :data:`upm.motion.dropouts.DROPOUT_JUMP_DEG`: 16_15's left arm reads zero for its
    #: first 2 frames, then jumps by 76 degrees).
    jump_deg: float = DROPOUT_JUMP_DEG


@dataclass(frozen=True)
class ReferenceConfig:
    """The reference as the balance controller follows it
    (:func:`controller.balance.follow.prepared_reference`)."""

    #: Cut-off of the zero-phase low-pass applied to the targets, Hz: mocap glitches are
    #: not targets, and the targets' accelerations are their second differences (the
    #: residual check's filter, :attr:`ResidualConfig.lowpass_hz`, has the same cut-off
    #: for the same reason; they are two settings so that one can change without the other).
    lowpass_hz: float = 12.0
    #: The start's lowest point is this far into the floor, m (a contact from the first
    #: step; mocap feet hover or sink by centimetres).
    start_depth_m: float = 0.001


@dataclass(frozen=True)
class GroundingConfig:
    """Every standing frame of the reference put on the floor (:mod:`controller.grounding`)."""

    #: The lowest point of a standing frame is put this far into the floor, m.
    depth_m: float = 0.001
    #: Cut-off of the zero-phase low-pass applied to the height shift, Hz (so that it adds
    #: no jerk of its own).
    shift_hz: float = 2.0


@dataclass(frozen=True)
class TrackingConfig:
    """The balance controller's PD tracking (:func:`controller.balance.control.tracking_gains`):
    ``qdd_des = qdd_ref + kp e + kd (qd_ref - qd)``."""

    #: Natural frequency of the hinges' tracking, Hz.
    joint_hz: float = 5.0
    #: Natural frequency of the root's rotation, Hz.
    root_rotation_hz: float = 3.0
    #: Natural frequency of the root's height, Hz.
    root_height_hz: float = 2.0
    #: Damping of the root's horizontal velocity, 1/s: its horizontal position is not
    #: tracked at all (the character may drift from the reference's path: the drift is
    #: reported as ``root_drift_m`` rather than fought).
    root_horizontal_damping_per_s: float = 10.0
    #: Damping ratio of every tracked degree of freedom.
    damping_ratio: float = 1.0
    #: Largest desired acceleration, rad/s^2 or m/s^2: a glitch in the reference (16_15
    #: jumps by 30 degrees for 2 frames at its start) must not ask for more than the body
    #: can do.
    max_acceleration: float = 300.0
    #: Targets are kept this far inside each hinge's range, degrees (the limits' forces are
    #: not in the plan).
    limit_margin_deg: float = 2.0


@dataclass(frozen=True)
class QPWeights:
    """The whole-body QP's least-squares weights (:mod:`controller.balance.wbc`), per unit
    of acceleration (m/s^2 or rad/s^2)."""

    root_rotation: float = 10.0
    root_yaw: float = 1.0
    root_height: float = 3.0
    root_horizontal: float = 10.0
    joints: float = 1.0
    #: The spine's and neck's rows (:attr:`SpineConfig.bodies`) while the spine is held to
    #: the clip's posture, times ``joints``.
    spine: float = 3.0
    contact: float = 100.0
    force: float = 1e-2
    torque: float = 0.3
    #: The root rows' weights times this without floor contact: then nothing but the
    #: limbs' reaction turns the root, and asking for a root acceleration would only fling
    #: the limbs.
    flight_root: float = 0.01


@dataclass(frozen=True)
class ContactConfig:
    """The floor contacts in the whole-body QP (:mod:`controller.balance.wbc`)."""

    #: Friction coefficient of the plan's 4-edge pyramid, below the simulated floor's 1.0
    #: (the model's geom friction) so that the planned forces stick. Not the residual
    #: check's :attr:`ResidualConfig.friction`: that one asks what the floor could supply
    #: at most, this one what the plan may count on.
    friction: float = 0.8
    #: Desired contact-point acceleration per unit of its velocity, 1/s (``-k v_c``).
    damping_per_s: float = 20.0


@dataclass(frozen=True)
class SolverConfig:
    """The whole-body QP's solver (:mod:`controller.balance.wbc`): its warm start and its
    tolerances. They are tight enough that the warm start and a solve from scratch give the
    same torques to about 1e-5 N m (the QP is nearly flat in how the weight is shared
    among the contact edges, so a looser multiplier test accepts points whose torques
    differ by newton-metres)."""

    #: A hinge's torque bounds enter the first solve when its applied torque is within this
    #: share of its strength of a bound.
    near_bound_share: float = 0.2
    #: A solution breaks a bound when it passes it by more than this share of the strength.
    bound_tolerance_share: float = 1e-9
    #: A torque within this share of the joint's strength of a bound is at it (the warm
    #: start's guess from the applied torques; the balance controller's saturation share).
    at_bound_share: float = 1e-6
    #: A guessed active set is wrong where an edge magnitude (body weights) is below minus
    #: this ...
    force_tolerance_bw: float = 1e-12
    #: ... or a multiplier below minus this times 1 + the largest linear term of the QP.
    multiplier_tolerance: float = 1e-14


@dataclass(frozen=True)
class SpineConfig:
    """The spine held to the clip's posture (:class:`controller.balance.control.BalanceControl`,
    in the modes that hold it: :attr:`Mode.spine_held`)."""

    #: The bodies whose hinges are the spine's and the neck's (:attr:`QPWeights.spine`).
    bodies: tuple[str, ...] = ("lowerback", "upperback", "thorax", "lowerneck", "upperneck",
                               "head")
    #: The spine is held while the character's capture offset is within this of the
    #: reference's, m (:func:`controller.balance.placement.capture_error_m`) ...
    held_m: float = 0.20
    #: ... left free from this, linearly between, m: the trunk is then left free to
    #: balance the body.
    free_m: float = 0.40


@dataclass(frozen=True)
class PlacementConfig:
    """Foot placement (:mod:`controller.balance.placement`): the swing foot moved by the
    difference between the character's and the reference's capture offsets."""

    #: Correct the swing foot's placement at all.
    enabled: bool = True
    #: Share of the capture-offset difference the swing foot is moved by: the default
    #: mode's gain, that of every mode that does not name its own
    #: (:attr:`Mode.placement_gain`), and the first the lookahead chooses among
    #: (:attr:`LookaheadConfig.other_gains`).
    gain: float = 0.3
    #: The largest shift of the swing foot, m.
    max_shift_m: float = 0.25
    #: A reference foot is down when its ankle moves slower than this, m/s ...
    foot_down_speed_mps: float = 0.8
    #: ... and is within this height of its lowest in the motion, m.
    foot_down_height_m: float = 0.08
    #: Also keep the swing ankle at least at the reference's height (hip and knee): a toe
    #: that scrapes trips.
    swing_height: bool = True
    #: Extra height of the swing ankle above the reference's while the reference swings
    #: it, m (where a mode names none; the modes choose their own).
    swing_clearance_m: float = 0.0
    #: Damping of the swing leg's inverse kinematics, m: a near-singular leg (a straight
    #: knee) is not asked for a huge turn
    #: (:func:`controller.balance.leg_kernels.damped_least_squares`).
    ik_damping_m: float = 0.05
    #: The largest change of one swing-leg joint's target, degrees.
    max_turn_deg: float = 45.0


@dataclass(frozen=True)
class FootTiltConfig:
    """A foot in the air kept at the reference's tilt (:mod:`controller.balance.foot_tilt`):
    the hip and knee changes of the placement would tilt the sole with them."""

    enabled: bool = True
    #: Damping of the ankle's least-squares turn, per radian squared: it keeps the solve
    #: regular where the hinge axes line up, and is small, so that the CMU ankle's second
    #: hinge, near vertical, still turns the foot about the shank by a few degrees where
    #: the roll asks for it (that hinge has little roll to give: the roll is put back in
    #: part).
    damping: float = 1e-3


@dataclass(frozen=True)
class ToesConfig:
    """A toe pressed on the floor lies flat
    (:meth:`controller.balance.control.BalanceControl._flatten_toes`)."""

    #: A toe hinge that turns the toe's axis up or down slower than this (per radian, near
    #: a vertical hinge) is not flattened.
    min_pitch_rate: float = 0.2


@dataclass(frozen=True)
class Mode:
    """One way of running the balance controller (:attr:`ControllerConfig.modes`).

    Attributes
    ----------
    placement_gain : float or None
        The foot-placement gain (None: :attr:`PlacementConfig.gain`).
    swing_contacts_excluded : str
        Which floor contacts of the foot the reference has in the air are not planned as
        support: ``"none"``; ``"swing toes"`` (a swing toe that scrapes the floor is not
        pinned to it); ``"foot"`` (no contact of that foot).
    swing_clearance_m : float
        The swing ankle's clearance above the reference's, m
        (:mod:`controller.balance.placement`).
    spine_held : bool
        Whether the spine is held to the clip's posture while the character's capture
        offset is near the reference's (:class:`SpineConfig`; where it is not, the hips
        and the trunk are left to balance the body).
    """

    placement_gain: float | None = None
    swing_contacts_excluded: str = "none"
    swing_clearance_m: float = 0.0
    spine_held: bool = False


#: The controller's modes, tried in this order where the default leads to trouble (the
#: first is the default). In every mode a toe pressed on the floor lies flat.
MODES = (Mode(None, "none", 0.0, True), Mode(None, "none", 0.04, False),
         Mode(0.6, "none", 0.02, False), Mode(None, "swing toes", 0.04, False),
         Mode(0.6, "swing toes", 0.04, False), Mode(None, "foot", 0.04, False))


@dataclass(frozen=True)
class SearchConfig:
    """The backtracking search over the modes (:mod:`controller.balance.search`, after
    SAMCON)."""

    #: Each segment of this many seconds runs in one mode ...
    segment_s: float = 0.25
    #: ... a segment in trouble (pelvis this far below the reference's, m, or its up axis
    #: this far from vertical and :attr:`trouble_tilt_margin_deg` beyond the reference's
    #: tilt, or the head :attr:`trouble_head_drop_m` below the reference's: bent over at
    #: the waist with the pelvis still up) is run again in the next mode, then its
    #: predecessors, up to :attr:`max_backtrack` segments back ...
    trouble_drop_m: float = 0.12
    #: The pelvis's up axis's least vertical component out of trouble (a cosine).
    trouble_up: float = 0.8
    #: The head's drop below the reference's that is trouble, m.
    trouble_head_drop_m: float = 0.25
    #: A pelvis tilted past :attr:`trouble_up` is trouble only where it is tilted this
    #: much further than the reference's, degrees: 02_10 (wash self) bends over with its
    #: pelvis 43 deg from vertical, and the test, which did not look at the reference, sent
    #: the search after the clip's own posture. Where the reference tilts less than about
    #: 22 deg (every frame of issue 10's 315 references: at most 14.3 deg, 05_01) nothing
    #: changes.
    trouble_tilt_margin_deg: float = 15.0
    #: Segments back (4 s: on 16_15 -> 16_15 the attempt that stands differs from the one
    #: that falls in a segment 3.5 s before the trouble; 10 s made the same runs) ...
    max_backtrack: int = 16
    #: ... and the segments after a changed one keep its mode for this long, s ...
    sticky_s: float = 2.0
    #: ... within this many times the reference's physics steps in all (0: no search; 30,
    #: not 15: on issue 10's rows every exact reference stands, the 02 walk sequence with
    #: `upm` windows too, which falls at 15 with the budget spent; offset seeds 11-20, not
    #: looked at when 30 was chosen, fall 11 times in 110 against 25, with the search
    #: before its sweep; only runs that spend more than 15 cost more).
    budget: float = 30.0
    #: The modes the sweep tries, in this order (indices into the modes, ascending); the
    #: others only in the combinations. In the sweep the last (no contact of the swing foot
    #: planned) ran 43 % of the rerun work and got past 13 % of the troubles, and mode 2
    #: (gain 0.6, the swing foot 2 cm up) then ran 14 % and got past 6 %. Over issue 10's
    #: runs, seeds 0-20, each left out in turn made as many falls (8 whole, 0 cut); the last
    #: with 18 % fewer segments run again, mode 2 with 2 % more whole and 15 % fewer cut,
    #: and 35_01 followed closer (its median body error 52 -> 43.5 mm).
    sweep_modes: tuple[int, ...] = (1, 3, 4)


@dataclass(frozen=True)
class LookaheadConfig:
    """The default mode's foot-placement gain, chosen by lookahead rollouts
    (:mod:`controller.balance.gain_selection`, :mod:`controller.balance.lookahead`)."""

    #: The gains weighed against :attr:`PlacementConfig.gain` (chosen among in the order
    #: ``(gain, *other_gains)``, the first on ties; none: no lookahead) ...
    other_gains: tuple[float, ...] = (0.6,)
    #: ... every this many seconds ...
    every_s: float = 0.5
    #: ... each rolled out this far ahead, s ...
    horizon_s: float = 1.0
    #: ... and chosen again half-way to the next choice where the chosen gain's rollout
    #: cost more than this (:func:`controller.balance.lookahead.rollout_cost`: a clean 1 s
    #: of a walk costs about 1, mostly the pace's error; one heading for a fall, tens).
    refine_cost: float = 1.5
    #: Weight of the root's horizontal velocity error in a rollout's cost, s (m/s to m): a
    #: small term that tells apart rollouts that stay up equally well by how closely they
    #: keep the reference's pace and direction (on 02_02 it picks the gain that needs no
    #: search).
    velocity_weight_s: float = 0.03


@dataclass(frozen=True)
class FallsConfig:
    """When a simulated character has fallen (:mod:`controller.falls`), and what the
    balance controller does then."""

    #: Fallen: pelvis or head below this share of its standing height (the reference's
    #: not) ...
    fraction: float = 0.5
    #: ... and more than this share of its standing height below the reference's. On 02_06
    #: (bend over and scoop up) the character's head passed half its standing height 4 cm
    #: under the reference's, which it was following down and up again: without the margin,
    #: a fall at 0.98 s. Only a reference that comes within this margin of the threshold is
    #: judged differently (of the data's clips, 02_06, 02_10 and 05_06).
    margin: float = 0.1
    #: Seconds the balance controller simulates after a fall before the run stops.
    after_fall_s: float = 1.0


@dataclass(frozen=True)
class WindowRunsConfig:
    """The free-root run around each window of a report
    (:func:`controller.analysis.window_free_runs`)."""

    #: The run starts this long before the window, s ...
    lead_s: float = 0.5
    #: ... and ends this long after it, s.
    tail_s: float = 0.5


@dataclass(frozen=True)
class ResidualConfig:
    """The inverse-dynamics residual check (:func:`controller.checks.dynamics.root_residual`)
    of ``upm check`` and ``upm simulate``."""

    #: Cut-off of the low-pass filter applied before differentiating, Hz. Mocap noise,
    #: twice differentiated, swamps the physics otherwise: on the walk 02_01 the needed
    #: force averages 1.57 body weights unfiltered (walking needs 1.0 on average) and 1.01
    #: filtered, and the residual drops from 0.41 to 0.04 body weights.
    lowpass_hz: float = 12.0
    #: Geoms within this distance of the floor can be pushed by it, m. Motion-capture feet
    #: on the model hover: in the flat walks of subjects 02, 05, 16 and 35 the lowest point
    #: of a frame is 0.8-2.5 cm above the floor at the median, 1.4-3.7 cm at the 75th
    #: percentile; with 3 cm the walk 02_01 would need 0.38 body weights of residual force
    #: on average (the stance foot out of reach), with 5 cm 0.04, with 8 cm 0.02.
    support_distance_m: float = 0.05
    #: Friction coefficient of the support pyramid: the simulated floor's own (the model's
    #: geom friction, 1.0), since the check asks what a contact could supply at most. The
    #: controller's pyramid (:attr:`ContactConfig.friction`) is lower on purpose.
    friction: float = 1.0
