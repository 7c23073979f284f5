r"""The desktop arm's firmware -- the arm is a uFactory uArm Swift Pro: its model, limits, G-code.

The lab report never names its arm, but its program does: it switches the suction cup with
``swift.send_cmd_async('M2231 V1')``, the pump command of the uArm Swift Pro's firmware sent
through UFactory's Python SDK (whose arm object is ``SwiftAPI``). The rest agrees: the
firmware's forward model (``getXYZFromAngle`` in UFactory's SwiftProForArduino) is the
lab's (answer 4),

.. math::

   s &= L_{low}\cos L + L_{up}\cos R + L_2 + f,\qquad
   h = L_{low}\sin L - L_{up}\sin R + L_1 - h_0,\\
   x &= s\sin B,\qquad y = -s\cos B,

with the motor angles :math:`(B, L, R)` of the base, the lower ("left") and the upper
("right") arm in degrees, UFactory's lengths :math:`L_{low} = 142.07`,
:math:`L_{up} = 158.81`, :math:`L_2 = 13.2`, :math:`L_1 = 106.6` mm and the suction cup's
offsets :math:`f = 56.65`, :math:`h_0 = 74.55` mm. Term by term it is the lab's model with
:math:`l_1 = L_{low}`, :math:`l_2 = L_{up}`, :math:`l_3 = L_2 + f = 69.85`,
:math:`l_0 - l_4 = L_1 - h_0 = 32.05` mm (the lab identified 144, 162, 67 and 35 mm) and

.. math:: B = 180^\circ - q_0,\qquad L = q_1,\qquad R = q_2,

so that the firmware's :math:`(x, y, z)` are the lab's. The arm's rest posture,
:math:`(B, L, R) = (90, 90, 0)`, is the lab's start point :math:`p_i` (answer 12).

The firmware reads G-code lines on its USB serial port (UFactory's *uArm Swift Pro
Protocol*). A plan of
:mod:`dqlab.pick_place` becomes (:func:`gcode_from_plan`):

* ``G0 X.. Y.. Z.. F..`` -- move the cup to a point of the base frame (mm, speed in mm/min);
  the firmware solves its own inverse model, with UFactory's lengths, and moves the three
  motors together (``G2202 N0`` to ``N2`` would set one motor angle at a time, one motor after
  the other);
* ``G2202 N3 V..`` -- turn the hand (wrist) servo to an angle in degrees, 0 to 180;
* ``M2231 V1`` / ``M2231 V0`` -- suction pump on / off;
* ``G2004 P..`` -- wait until the arm has arrived, then wait that many milliseconds.

The firmware is built on Grbl 0.9: it reads a line up to ``\n`` or ``\r``, throws away what
follows a ``;`` (a comment), and picks the characters ``?``, ``!``, ``~``, ``@`` and
Ctrl-X off the serial stream wherever they stand, even inside a comment (status report, feed
hold, cycle start, safety door, reset). So the program's name, the one text it carries, goes
into a comment and must be one line of printable ASCII without those five characters
(:data:`GCODE_REALTIME`); numbers are written with fixed decimals, feeds as whole mm/min up to
the firmware's maximum rate (:data:`MAX_FEED`), and a dwell longer than a 16-bit ``P`` word
holds is split.

The firmware switches the pump and turns the hand servo as soon as it reads the line, while
moves are queued, so the program waits for the arm to arrive (``G2004 P0``) before each of
them. The plan's joint targets (the lab's angles, from the identified model) and the motor
angles the firmware will compute go along as comments, and every point is checked against
the firmware's own limits before a line is written: the base turns over :math:`[0, 180]`
degrees (the firmware serves the half space :math:`x \ge 0` only),
:math:`0 \le L \le 135.6`, :math:`0 \le R \le 119.9` and :math:`29 \le L + R \le 170` degrees.
"""

import math

import numpy as np

from . import ik
from ._checks import as_float_array, check_instance, check_path, check_scalar, check_text
from ._files import write_atomically
from .models import desk_arm_lab_from_joints
from .pick_place import PickPlacePlan
from .robot import Link, Robot

__all__ = ["LENGTHS", "MOTOR_LIMITS_DEG", "MAX_FEED", "GCODE_REALTIME", "model",
           "motor_angles_from_lab", "lab_angles_from_motor", "motor_angles", "gcode_from_plan",
           "write_gcode"]

#: UFactory's nominal dimensions of the uArm Swift Pro with its suction cup, metres (firmware
#: constants ``MATH_LOWER_ARM``, ``MATH_UPPER_ARM``, ``MATH_L2``, ``MATH_L1`` and the
#: default front and height offsets of the cup).
LENGTHS = {"lower_arm": 0.14207, "upper_arm": 0.15881, "l2": 0.0132, "l1": 0.1066,
           "front": 0.05665, "height": 0.07455}

#: The firmware's limits on the motor angles, degrees: base ``B``, lower arm ``L``, upper
#: arm ``R``, their sum, and the hand servo.
MOTOR_LIMITS_DEG = {"B": (0.0, 180.0), "L": (0.0, 135.6), "R": (0.0, 119.9),
                    "L + R": (29.0, 170.0), "hand": (0.0, 180.0)}

#: The fastest feed a program may ask for, mm/min: the firmware's default maximum rate
#: (``DEFAULT_X_MAX_RATE`` of SwiftProForArduino's ``defaults_generic.h``).
MAX_FEED = 100_000

#: The characters the firmware (Grbl 0.9's serial interrupt) obeys wherever they stand, even
#: in a comment: status report, feed hold, cycle start, safety door; Ctrl-X (reset) is a
#: control character, refused with the others.
GCODE_REALTIME = "?!~@"

#: The longest wait of one ``G2004 P..`` line, ms: the firmware reads ``P`` with ``%d``, a
#: 16-bit integer on the arm's ATmega2560 (at most 32767).
_MAX_WAIT_MS = 30_000

#: The longest dwell written, seconds (an hour: a longer one is a mistake of units).
_MAX_DWELL = 3600.0


def model() -> Robot:
    r"""The desktop arm as its firmware models it: the chain of :func:`dqlab.models.desk_arm`
    with UFactory's lengths of the uArm Swift Pro and its suction cup (:data:`LENGTHS`).

    The lab's model with UFactory's lengths: :math:`l_1 = 142.07`, :math:`l_2 = 158.81`,
    :math:`l_3 = 13.2 + 56.65` and :math:`l_0 - l_4 = 106.6 - 74.55` mm.

    Returns
    -------
    Robot

    Examples
    --------
    The rest posture, motor angles :math:`(B, L, R) = (90, 90, 0)` degrees:

    >>> import numpy as np
    >>> from dqlab.models import desk_arm_joints_from_lab
    >>> arm = model()
    >>> q_lab = lab_angles_from_motor(np.radians([90.0, 90.0, 0.0]))
    >>> (arm.fk(desk_arm_joints_from_lab(q_lab))[:3, 3] * 1000).round(2) + 0.0
    array([228.66,   0.  , 174.12])
    """
    p = LENGTHS
    lim = (-math.pi, math.pi)
    links = [Link(a=p["l2"] + p["front"], alpha=math.pi / 2, d=p["l1"] - p["height"],
                  limits=lim),
             Link(a=p["lower_arm"], alpha=0.0, d=0.0, limits=lim),
             Link(a=p["upper_arm"], alpha=0.0, d=0.0, limits=lim)]
    return Robot(links, convention="dh", name="uArm Swift Pro (suction cup)")


def motor_angles_from_lab(q_lab):
    r"""The uArm's motor angles :math:`(B, L, R) = (\pi - q_0, q_1, q_2)` from the lab's.

    Parameters
    ----------
    q_lab : array_like, shape (..., 3)
        The lab's :math:`(q_0, q_1, q_2)`, radians.

    Returns
    -------
    ndarray, shape (..., 3)
        Radians. The map is its own inverse (:func:`lab_angles_from_motor`).

    Examples
    --------
    >>> import numpy as np
    >>> np.degrees(motor_angles_from_lab(np.radians([0.0, 77.3, 63.9]))).round(1)
    array([180. ,  77.3,  63.9])
    """
    q = as_float_array(q_lab, "q_lab", (3,))
    return np.stack([math.pi - q[..., 0], q[..., 1], q[..., 2]], axis=-1)


#: The lab's angles from the motor angles: the same involution as
#: :func:`motor_angles_from_lab`.
lab_angles_from_motor = motor_angles_from_lab


def motor_angles(positions, *, where="point"):
    r"""The motor angles the firmware computes for cup positions, checked against its limits.

    The closed-form inverse model (:func:`dqlab.ik.desk_arm_closed_form.desk_arm`) of
    :func:`model`, facing the point with the elbow up, as the firmware solves it.

    Parameters
    ----------
    positions : array_like, shape (K, 3)
        Cup positions in the base frame, metres.
    where : str, optional
        How to name a point in an error message (``"point"``, named with its index in
        ``positions``; ``"step"``).

    Returns
    -------
    ndarray, shape (K, 3)
        :math:`(B, L, R)` in degrees.

    Raises
    ------
    ValueError
        Naming the first point that the firmware cannot reach or that breaks one of
        :data:`MOTOR_LIMITS_DEG`.

    Examples
    --------
    >>> motor_angles([[0.0, 0.17, 0.03]]).round(1)
    array([[180. ,  78.7,  62.9]])
    >>> motor_angles([[0.0, -0.17, 0.5]])
    Traceback (most recent call last):
    ...
    ValueError: point 0 (positions[0]): (0, -170, 500) mm is out of the uArm Swift Pro's ...
    """
    p = as_float_array(positions, "positions", (3,))
    if p.ndim != 2:
        raise ValueError(f"positions must have shape (K, 3), got {p.shape}")
    check_text(where, "where", max_length=40)
    far = np.flatnonzero(np.hypot(np.hypot(p[:, 0], p[:, 1]), p[:, 2]) > _REACH)
    if far.size:                                   # refused before solving (no overflow)
        k = int(far[0])
        raise ValueError(f"{_label(where, k)}: ({', '.join(f'{v:.4g}' for v in p[k] * 1000)}) mm "
                         f"is out of the uArm Swift Pro's reach: more than {_REACH:g} m from "
                         "its base")
    result = ik.desk_arm(model(), p)
    angles = np.full((len(p), 3), np.nan)
    for k in range(len(p)):
        name = "(" + ", ".join(f"{round(v, 6) + 0.0:.4g}" for v in p[k] * 1000) + ") mm"
        where_k = _label(where, k)
        if not result.valid[k, 0]:
            reason = str(result.reason[k]).removeprefix("unreachable: ")
            raise ValueError(f"{where_k}: {name} is out of the uArm Swift Pro's reach: "
                             f"{reason}")
        q_lab = desk_arm_lab_from_joints(result.solutions[k, 0])
        B, L, R = np.degrees(motor_angles_from_lab(q_lab))
        checks = {"B": B, "L": L, "R": R, "L + R": L + R}
        for label, value in checks.items():
            lo, hi = MOTOR_LIMITS_DEG[label]
            if not lo - 1e-9 <= value <= hi + 1e-9:
                raise ValueError(f"{where_k}: {name} needs {label} = {value:.2f} deg, "
                                 f"outside the firmware's range [{lo:g}, {hi:g}] deg")
        angles[k] = B, L, R
    return angles


#: Farther than this from the base (metres), no point is within the arm's reach (its arms
#: and the cup's offsets add up to 0.37 m).
_REACH = 1.0


def _label(where, k):
    """How an error names point ``k``: "point 0 (positions[0])", or "step 0"."""
    return f"{where} {k}" + (f" (positions[{k}])" if where == "point" else "")


def _arrivals(plan):
    """Per step: (sample where the arm arrives, seconds of the move, dwell, suction after).

    The arm has arrived at a step's target from the first sample of the step's trailing run
    of samples at rest on the target (the segment's last sample, then the dwell).
    """
    t, q, qd, step = plan.t, plan.q, plan.qd, plan.step
    at_rest = np.all(np.abs(qd) <= 1e-12, axis=1)
    out = []
    for k in range(len(plan.targets)):
        samples = np.flatnonzero(step == k)
        resting = at_rest[samples] & np.all(np.abs(q[samples] - plan.targets[k]) <= 1e-12,
                                            axis=1)
        run = len(resting) - np.argmin(resting[::-1]) if not resting.all() else 0
        arrive = int(samples[run]) if run < len(samples) else int(samples[-1])
        before = int(samples[0]) - 1
        move = float(t[arrive] - t[before]) if before >= 0 else 0.0
        out.append((arrive, move, float(t[samples[-1]] - t[arrive]),
                    bool(plan.suction[samples[-1]])))
    return out


def gcode_from_plan(plan, *, name="pick and place", start_feed=3000):
    r"""The G-code program that plays a pick-and-place plan on a uArm Swift Pro.

    One block per step of the plan: wait for the arm, turn the hand servo if the step's
    wrist angle changes, ``G0`` to the step's cup position at the plan's average speed for
    that segment (distance over the segment's duration), and where the cup switches, wait
    for the arm, switch the pump (``M2231``) and dwell for the plan's dwell. The first step
    is where the arm starts: the program goes there first, with the pump off. The firmware
    solves each point with its own model (:func:`motor_angles`), so a point that the plan's
    model reaches may still be out of the arm's limits: it is refused here, by step.

    Parameters
    ----------
    plan : dqlab.pick_place.PickPlacePlan
        A plan of :func:`dqlab.pick_place.plan_pick_place` for :func:`dqlab.models.desk_arm`.
    name : str, optional
        The program's name, in its first comment line: one line of printable ASCII, at most
        80 characters, without the firmware's real-time characters :data:`GCODE_REALTIME`.
    start_feed : float, optional
        Speed of the first move, to the start point, mm/min: 1 to :data:`MAX_FEED`, written
        rounded to a whole mm/min.

    Returns
    -------
    str
        The program, one command per line, comments after ``;``; millimetres, mm/min,
        degrees and milliseconds.

    Raises
    ------
    ValueError
        Naming the argument (a ``name`` that is not one safe line, a ``start_feed`` that
        is not a number in range) or the first step whose point the firmware cannot reach
        within its limits (:func:`motor_angles`), whose wrist angle is outside the hand
        servo's 0 to 180 degrees, whose move needs a feed above :data:`MAX_FEED` or whose
        dwell is longer than an hour.
    TypeError
        If ``plan`` is not a :class:`~dqlab.pick_place.PickPlacePlan` or ``name`` not text.

    Examples
    --------
    >>> from dqlab import pick_place as pp
    >>> from dqlab.models import desk_arm
    >>> task = pp.task_from_lab([[0, 170, 80, 0, 0], [0, 170, 30, 1, 0],
    ...                          [0, 170, 80, 1, 0]])
    >>> program = gcode_from_plan(pp.plan_pick_place(desk_arm(), task))
    >>> for line in program.splitlines():
    ...     if line.startswith(("M2231", "G0 ")):
    ...         print(line)
    M2231 V0 ; pump off
    G0 X0.00 Y170.00 Z80.00 F3000
    G0 X0.00 Y170.00 Z30.00 F3884
    M2231 V1 ; pump on
    G0 X0.00 Y170.00 Z80.00 F3884
    M2231 V0 ; pump off
    """
    check_instance(plan, PickPlacePlan, "plan")
    check_text(name, "name", max_length=80, forbidden=GCODE_REALTIME,
               why="the firmware obeys them even in a comment")
    if not name.isascii():
        bad = next(k for k, c in enumerate(name) if not c.isascii())
        raise ValueError(f"name must be ASCII text (the program is an ASCII file): character "
                         f"{name[bad]!r} at position {bad} is not")
    start_feed = check_scalar(start_feed, "start_feed", minimum=1, maximum=MAX_FEED)
    targets = np.asarray(plan.targets)
    timing = _arrivals(plan)
    positions = plan.cup[[a for a, _, _, _ in timing], :3, 3]
    motors = motor_angles(positions, where="step")
    wrist = np.degrees(targets[:, 3])
    lo, hi = MOTOR_LIMITS_DEG["hand"]
    for k, w in enumerate(wrist):
        if not lo - 1e-9 <= w <= hi + 1e-9:
            raise ValueError(f"step {k}: wrist angle {w:.6g} deg is outside the hand servo's "
                             f"range [{lo:g}, {hi:g}] deg")
    lab = np.degrees(desk_arm_lab_from_joints(targets[:, :3]))
    mm = positions * 1000.0
    suction = [on for _, _, _, on in timing]
    lines = [f"; {name}: {len(targets)} steps, {plan.duration:.2f} s as planned",
             "; for a uFactory uArm Swift Pro with its suction cup (G-code over USB serial)",
             "; units: mm, mm/min, degrees, ms; frame: the arm's base frame, z up",
             "; per step: the plan's lab angles (q0, q1, q2) and the firmware's motors (B, L, R)",
             "M2231 V0 ; pump off"]
    previous_wrist = None
    for k in range(len(targets)):
        x, y, z = mm[k]
        lines.append(f"; step {k}: plan ({lab[k, 0]:.2f}, {lab[k, 1]:.2f}, {lab[k, 2]:.2f}), "
                     f"firmware ({motors[k, 0]:.2f}, {motors[k, 1]:.2f}, {motors[k, 2]:.2f}) deg")
        lines.append("G2004 P0 ; wait for the arm")
        if previous_wrist is None or wrist[k] != previous_wrist:
            lines.append(f"G2202 N3 V{wrist[k]:.2f} ; hand servo (wrist)")
            previous_wrist = wrist[k]
        _, seconds, dwell, _ = timing[k]
        if k == 0 or seconds <= 0:
            feed = round(start_feed)
        else:
            distance = float(np.linalg.norm(mm[k] - mm[k - 1]))
            feed = max(1, round(60.0 * distance / seconds))
            if feed > MAX_FEED:
                raise ValueError(f"step {k}: the plan moves {distance:.1f} mm in {seconds:.3g} s, "
                                 f"a feed of {feed:.3g} mm/min, above the firmware's maximum "
                                 f"{MAX_FEED} mm/min")
        lines.append(f"G0 X{x:.2f} Y{y:.2f} Z{z:.2f} F{feed}")
        switches = suction[k] != (suction[k - 1] if k else False)
        if switches:
            if not dwell <= _MAX_DWELL:
                raise ValueError(f"step {k}: a dwell of {dwell:.3g} s is longer than an hour "
                                 "(seconds taken for milliseconds?)")
            lines.append("G2004 P0 ; wait for the arm")
            lines.append(f"M2231 V{int(suction[k])} ; pump {'on' if suction[k] else 'off'}")
            wait = round(dwell * 1000)
            while True:            # one G2004 holds at most a 16-bit P: split a long dwell
                lines.append(f"G2004 P{min(wait, _MAX_WAIT_MS)} ; dwell while the cup switches")
                wait -= _MAX_WAIT_MS
                if wait <= 0:
                    break
    lines.append("G2004 P0 ; wait for the arm")
    lines.append("M2231 V0 ; pump off")
    return "\n".join(lines) + "\n"


def write_gcode(path, plan, **options):
    """Write :func:`gcode_from_plan` to a file; return its path.

    Parameters
    ----------
    path : str or Path
    plan : dqlab.pick_place.PickPlacePlan
    **options
        Passed to :func:`gcode_from_plan`.

    Returns
    -------
    Path

    Raises
    ------
    TypeError
        If ``path`` is not a file path.
    ValueError
        As :func:`gcode_from_plan`, before any file is opened; or if ``path`` is a directory.
    OSError
        If the file cannot be written. The file is written whole or not at all: a failed
        write leaves an existing file as it was (the content goes to a temporary file in the
        same folder, renamed over the old one once complete).
    """
    path = check_path(path)
    text = gcode_from_plan(plan, **options)
    return write_atomically(path, text, encoding="ascii")
