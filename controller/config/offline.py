"""The ``offline`` section of :class:`controller.config.ControllerConfig`: the offline
effort's sampling search over the servo targets (:mod:`controller.offline`, after SAMCON:
Liu et al. 2010, "Sampling-based contact-rich motion control")."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class OfflineWeights:
    """The weights of a state's cost against the reference
    (:func:`controller.offline.cost.state_cost`): each term is a squared error, so that
    a state at the reference costs 0 and one about 6 deg, 10 deg, 5 cm, 10 cm and 10 cm
    off in each term costs about 0.5, 0.6, 0.1, 0.5 and 0.4."""

    #: Sum over the hinges of the squared angle error, rad^2 (45 hinges 6 deg off: 0.49).
    pose: float = 1.0
    #: Squared angle between the pelvis's orientation and the reference's, rad^2 (20, not
    #: 4: on the walk 02_01, 0-239, with 120 samples, the pelvis's tilt was the first term
    #: to grow and the run fell at 1.45 s with 4, stood with 20).
    root: float = 20.0
    #: Squared error of the pelvis's height, m^2.
    height: float = 40.0
    #: Sum over the end effectors (head, hands, feet) of the squared error of their
    #: position in the pelvis's frame, m^2.
    end: float = 10.0
    #: Squared error of the capture point's horizontal offset from the middle of the feet
    #: (the reference's own offset is the target: the body over its support as the
    #: performer had it), m^2. The capture point, not the centre of mass: with the centre
    #: of mass, 02_10 (wash self, 0-399, 120 samples) drifted forward 6 cm in 0.9 s, no
    #: segment's samples could bring it back, and it fell at 2.23 s; with the capture point
    #: it stood (2.4 deg RMS).
    balance: float = 40.0


@dataclass(frozen=True)
class OfflineConfig:
    """The offline effort's search (:func:`controller.offline.perform`): segment by segment,
    corrections of the servo targets are sampled from the best states so far, rolled
    out in MuJoCo, and the best kept; where every sample is in trouble the search goes
    back up to :attr:`backtracks` segments."""

    #: Length of a segment, s (rounded to whole frames, at least one). 0.2, not SAMCON's
    #: 0.1: on the whole walk 02_01 (120 samples, root weight 20) 0.1 s with coherence 0.7
    #: fell at 2.77 s, 0.2 s with coherence 0.5 stood (joint error 3.9 deg RMS).
    segment_s: float = 0.2
    #: Rollouts per segment in all, spread evenly over the kept states.
    samples: int = 240
    #: States kept after each segment (the best by cost).
    keep: int = 12
    #: Standard deviation of a sampled correction of each servo's target, degrees.
    sigma_deg: float = 6.0
    #: Temporal coherence of the corrections: a segment's correction is this times its
    #: parent's plus ``sqrt(1 - coherence^2)`` times a fresh draw (0: independent
    #: segments; the targets are interpolated from the parent's correction to the new one
    #: over the segment, so they never jump).
    coherence: float = 0.5
    #: A sample is in trouble where its cost (mean over the segment's frames) is above
    #: this, or it has fallen (:mod:`controller.falls` with the ``falls`` section).
    trouble_cost: float = 2.0
    #: Where every sample of a segment is in trouble, the search goes back this many
    #: segments at most (1 the first time at that segment, then 2, ...) and samples again.
    backtracks: int = 3
    #: Added to the cost of a fallen state.
    fall_cost: float = 1e4
    #: The lookahead: the :attr:`lookahead_top` samples that cost least over their
    #: segment are rolled on for this long past it (their correction held; past the
    #: motion's end, its last targets held), and that tail's mean cost, times
    #: :attr:`lookahead_weight`, is added before the best are kept, so that a state already
    #: tipping over is not kept because its segment was close to the reference. 0: none.
    #: 0.4 (with the warm start), not 0: on the first 4 s of the train clips the real-time
    #: controller falls on, the karate kata 135_06 no longer ended going down and 01_01's
    #: error went from 4.4 to 3.6 deg RMS; the jump 02_04 and the dance 05_16 fell as
    #: before (1.90 s against 1.92, 1.54 against 1.41); it costs about a fifth more.
    lookahead_s: float = 0.4
    #: The samples rolled on past their segment, the best by the segment's cost.
    lookahead_top: int = 24
    #: The weight of the tail's mean cost (its fall, ``fall_cost``, added unweighted).
    lookahead_weight: float = 1.0
    #: Rank the samples upright first: a sample whose segment ends in trouble by the
    #: real-time search's test (the pelvis or the head too far below the reference's, or
    #: the pelvis tilted; the ``search`` section's ``trouble_*``), or whose lookahead tail
    #: does, or that was not looked ahead, is kept only after every sample that is out of
    #: trouble, whatever their costs. The cost weighs the whole posture, so a state going
    #: down can cost less than an upright one further from the reference's joint angles.
    #: True: on the first 4 s of six train clips it changed errors by 0.1 deg at most, and
    #: the jump 02_04, which fell at 1.90 s without it, stood (4.2 deg RMS).
    upright_first: bool = True
    #: The search simulates at most ``budget * samples`` times the motion's physics steps
    #: in all (and the lookahead's tails of each segment as many times): 1 is one pass of
    #: :attr:`samples` rollouts over every segment, with no room
    #: to go back; a backtrack is allowed only while the passes done, the ones it adds and
    #: one for each segment still ahead stay within it. At the defaults, 240 rollouts of
    #: 600 physics steps per simulated second make a pass (144,000 steps); 4 passes are at
    #: most 576,000 steps per simulated second (about 17 wall s at 34,000 steps/s on two
    #: cores, plus the cost's kinematics).
    budget: float = 4.0
    weights: OfflineWeights = field(default_factory=OfflineWeights)
    #: Search around the real-time balance controller's run, turned into servo targets
    #: (:mod:`controller.offline.warm`: its foot placement and balance in the targets the
    #: corrections are sampled around), instead of around the reference's targets.
    #: Where the real-time run falls, the search starts from the reference's targets.
    #: True: on the first 4 s of the train clips the search alone fell on though the
    #: real-time controller stands (the walks 02_02 and 05_01, the run 09_06, the bend
    #: 02_06), it stood on all four (1.5, 4.8, 3.6 and 4.0 deg RMS).
    warm_start: bool = True
    #: The warm start for the method ``performed`` (:mod:`controller.offline.performer`),
    #: which keeps the window as the body did it (the study's free-root test and ``upm
    #: simulate`` keep :attr:`warm_start`). False: on 16 pairs of the train split (seed 7,
    #: 20-frame windows) its windows were valid in 90.6 % of frames without the warm start
    #: against 83.8 % with it (feasible's, followed: 89.4), three times less jerky (805
    #: against 1,969 x 10^3 deg/s^3), at about the same foot skating (0.96 against 0.89
    #: m/s), nearest real posture (11.9 against 11.8 deg) and residual force (0.03
    #: against 0.02 body weights): the real-time controller's foot placement and balance,
    #: in the targets, are corrections the window then carries.
    performed_warm_start: bool = False
    #: The upper body's servos (every joint with no foot below it and not below a foot:
    #: :func:`controller.offline.samcon.upper_body_servos`) are sampled at this share of
    #: :attr:`sigma_deg`. 1: every servo alike.
    upper_sigma_share: float = 1.0
    #: :attr:`upper_sigma_share` for the method ``performed``, whose window is kept as the
    #: body did it. 0.5, not 1: on 24 pairs of the train split (seed 7, 20-frame windows)
    #: its windows' nearest real posture came 1.33 deg above UPM's windows' instead of
    #: 2.01, foot skating 0.81 m/s instead of 0.89, valid frames 88.8 % instead of 90.4
    #: (feasible's, followed: 89.0), residual force 0.044 body weights instead of 0.034.
    #: The corrections the search needs are in the legs; in the arms and the trunk, which
    #: carry no contact, they only take the window away from the asked one. On 12 of those
    #: pairs 0.25 gave 1.51 deg and 0.5 1.40.
    performed_upper_sigma_share: float = 0.5
    #: Threads of ``mujoco.rollout`` (the results do not depend on it).
    threads: int = 2
    #: Seed of the sampled corrections: the same seed, the same run, bit for bit.
    seed: int = 0
