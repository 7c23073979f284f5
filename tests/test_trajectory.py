"""Tests of dqlab.trajectory: time laws, joint trajectories, Cartesian paths, path following.

Oracles: the closed forms of the laws (end values, peaks, switch times of the UR3 report),
finite differences of the sampled arrays, scipy (quadrature, the clamped cubic spline),
pytransform3d (ScLERP), the robot's forward kinematics and ur_analytic_ik (UR3 IK).
"""


import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dqlab import quaternion_conjugate, quaternion_product, rot_x, rot_y, rot_z, transform_from
from dqlab.ik import ur
from dqlab.models import ur3, ur3_mdh
from dqlab.testing import quiet_stdout
from dqlab.trajectory import (
    CartesianPath,
    TimeLaw,
    Trajectory,
    circle_three_phase,
    cubic,
    follow_path_numerical,
    follow_path_ur,
    joint_trajectory,
    joint_velocities,
    line_slerp,
    quintic,
    screw_path,
    three_phase,
    time_grid,
    track_branches,
    trapezoidal,
    ur_singularity_margins,
    via_points,
)

#: the circle of chapter 11: centre, fixed tool orientation (tool z along -y), start
CENTER = np.array([0.0, -0.35, 0.25])
R_WT = rot_x(np.pi / 2)
R, V, DT = 0.1, 0.05, 0.005


@pytest.fixture(scope="module")
def robot():
    return ur3()


@pytest.fixture(scope="module")
def circle():
    return circle_three_phase(CENTER, R, V, DT, orientation=R_WT)


def central_difference(y, t):
    return np.gradient(y, t, axis=0)


# --------------------------------------------------------------------------------------
# time laws


@pytest.mark.parametrize("T, D", [(2.0, 1.0), (0.5, -3.0), (7.0, 0.25)])
def test_cubic_and_quintic_closed_forms(T, D):
    for law, v_peak, a_peak in ((cubic(T, D), 1.5, 6.0), (quintic(T, D), 1.875, 10 / np.sqrt(3))):
        s, sd, sdd = law(np.array([0.0, T / 2, T]))
        assert s.tolist() == pytest.approx([0.0, D / 2, D], abs=1e-14)
        assert sd[[0, 2]].tolist() == [0.0, 0.0]
        assert law.peak_speed == pytest.approx(v_peak * abs(D) / T, rel=1e-12)
        assert abs(sd[1]) == pytest.approx(v_peak * abs(D) / T, rel=1e-12)
        assert law.peak_acceleration == pytest.approx(a_peak * abs(D) / T**2, rel=1e-9)
    assert quintic(T, D).acceleration(np.array([0.0, T])).tolist() == [0.0, 0.0]
    assert quintic(T, D).jerk(0.0) == pytest.approx(60 * D / T**3, rel=1e-12)
    assert cubic(T, D).jerk(T / 3) == pytest.approx(-12 * D / T**3, rel=1e-12)


def test_trapezoid_accelerating_for_a_third_peaks_at_1_5_delta_over_T():
    law = trapezoidal(0.9, duration=3.0)
    assert law.peak_speed == pytest.approx(1.5 * 0.9 / 3.0, rel=1e-14)
    assert law.switch_times.tolist() == pytest.approx([1.0, 2.0], rel=1e-14)
    assert law.peak_acceleration == pytest.approx(0.45 / 1.0, rel=1e-14)


@settings(max_examples=60, deadline=None)
@given(D=st.floats(1e-3, 10), v=st.floats(0.05, 5), a=st.floats(0.05, 20),
       sign=st.sampled_from([-1.0, 1.0]))
def test_trapezoid_within_limits_is_the_shortest(D, v, a, sign):
    law = trapezoidal(sign * D, v_max=v, a_max=a)
    assert law.peak_speed <= v * (1 + 1e-12)
    assert law.peak_acceleration <= a * (1 + 1e-12)
    assert law.distance == pytest.approx(sign * D, rel=1e-12)
    # shortest time: cruise at v_max when reachable, else the triangle
    T = D / v + v / a if D > v * v / a else 2 * np.sqrt(D / a)
    assert law.duration == pytest.approx(T, rel=1e-12)
    # and the profile reaches the binding limit
    assert law.peak_acceleration == pytest.approx(a, rel=1e-12)


@pytest.mark.parametrize("kwargs", [dict(duration=2.0, a_max=2.5), dict(duration=2.0, v_max=0.7),
                                    dict(duration=2.0, v_max=5.0),
                                    dict(duration=2.0, accel_fraction=0.5),
                                    dict(duration=2.0, a_max=1.0)])
def test_trapezoid_from_a_duration_ends_on_time(kwargs):
    law = trapezoidal(1.0, **kwargs)
    assert law.duration == pytest.approx(2.0, rel=1e-14)
    assert law.distance == pytest.approx(1.0, rel=1e-12)
    if "a_max" in kwargs:
        assert law.peak_acceleration == pytest.approx(kwargs["a_max"], rel=1e-9)
    if "v_max" in kwargs:
        assert law.peak_speed <= kwargs["v_max"] * (1 + 1e-12)


def test_three_phase_matches_the_report():
    law = three_phase(2 * np.pi * R, V)
    t1, t2 = law.switch_times
    assert t1 == pytest.approx(np.pi * R / V, rel=1e-14)
    assert t2 == pytest.approx(3 * np.pi * R / (2 * V), rel=1e-14)
    assert law.duration == pytest.approx(3.5 * np.pi * R / V, rel=1e-14)
    a = law.acceleration(np.array([t1 / 2, (t1 + t2) / 2, (t2 + law.duration) / 2]))
    assert a.tolist() == pytest.approx([V**2 / (np.pi * R), 0.0, -V**2 / (2 * np.pi * R)],
                                       rel=1e-12)
    s = law.position(np.array([t1, t2, law.duration]))
    assert s.tolist() == pytest.approx([np.pi * R / 2, np.pi * R, 2 * np.pi * R], rel=1e-13)
    assert law.peak_speed == pytest.approx(V, rel=1e-14)


LAWS = [cubic(1.3, 2.0), quintic(0.7, -1.0), trapezoidal(1.0, v_max=0.5, a_max=1.0),
        trapezoidal(0.1, v_max=0.5, a_max=1.0), three_phase(2.0, 0.4, (0.1, 0.6, 0.3)),
        three_phase(1.0, 1.0, (0.5, 0.0, 0.5))]


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_position_and_speed_are_continuous_at_the_switches(law):
    for tk in law.breaks:
        eps = 1e-9 * max(law.duration, 1.0)
        before, after = law(tk - eps), law(tk + eps)
        assert after[0] == pytest.approx(before[0], abs=1e-8)
        assert after[1] == pytest.approx(before[1], abs=1e-8)


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_integral_of_speed_is_the_distance(law):
    from scipy.integrate import quad

    integral, _ = quad(law.speed, 0.0, law.duration, points=law.breaks[1:-1], epsabs=1e-13)
    assert integral == pytest.approx(law.distance, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("law", LAWS, ids=lambda law: law.name)
def test_derivatives_agree_with_finite_differences(law):
    t = np.linspace(0, law.duration, 20001)
    s, sd, sdd = law(t)
    inner = slice(2, -2)
    assert np.allclose(central_difference(s, t)[inner], sd[inner], atol=1e-6 * law.peak_speed
                       + 1e-3 * law.peak_speed * (len(law.breaks) > 2))
    # the acceleration away from its jumps
    far = np.min(np.abs(t[:, None] - law.breaks[None, :]), axis=1) > 1e-3 * law.duration
    assert np.allclose(central_difference(sd, t)[far], sdd[far],
                       atol=1e-6 * law.peak_acceleration)


def test_laws_hold_before_and_after_and_broadcast():
    law = quintic(2.0, 3.0)
    s, sd, sdd = law(np.array([[-1.0, 0.5], [2.0, 5.0]]))
    assert s.shape == (2, 2)
    assert s[0, 0] == 0.0 and s[1, 1] == 3.0 and sd[1, 1] == 0.0 and sdd[0, 0] == 0.0
    assert float(law.position(0.5)) == s[0, 1]


def test_time_grid():
    assert time_grid(3.5 * np.pi * R / V, DT, endpoint=False).size == 4399
    t = time_grid(1.0, 0.3)
    assert t.tolist() == pytest.approx([0.0, 0.3, 0.6, 0.9, 1.0])
    t = time_grid(1.0, 0.25)
    assert t.size == 5 and t[-1] == 1.0
    assert time_grid(0.0, 0.1).tolist() == [0.0]


@pytest.mark.parametrize("call, match", [
    (lambda: cubic(-1.0), "duration"),
    (lambda: quintic(0.0), "duration"),
    (lambda: cubic(1.0, np.nan), "distance"),
    (lambda: trapezoidal(1.0, duration=1.0, a_max=3.0), "a_max"),
    (lambda: trapezoidal(1.0, duration=1.0, v_max=1.0), "v_max"),
    (lambda: trapezoidal(1.0, v_max=1.0), "give v_max and a_max"),
    (lambda: trapezoidal(0.0, v_max=1.0, a_max=1.0), "distance"),
    (lambda: trapezoidal(1.0, v_max=-1.0, a_max=1.0), "v_max"),
    (lambda: trapezoidal(1.0, duration=1.0, accel_fraction=0.6), "accel_fraction"),
    (lambda: trapezoidal(1.0, duration=1.0, a_max=10.0, v_max=1.0), "v_max"),
    (lambda: three_phase(1.0, 1.0, (0.5, 0.6, 0.1)), "sum to 1"),
    (lambda: three_phase(1.0, 1.0, (0.0, 0.5, 0.5)), "fractions"),
    (lambda: three_phase(1.0, 0.0), "speed"),
    (lambda: time_grid(1.0, 0.0), "dt"),
    (lambda: time_grid(1.0, -0.1), "dt"),
    (lambda: time_grid(-1.0, 0.1), "duration"),
    (lambda: TimeLaw(np.array([0.0, 1.0, 1.0]), np.zeros((2, 6))), "increase"),
    (lambda: quintic(1.0).sample(np.nan), "dt"),
])
def test_time_law_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_a_scalar_that_is_not_a_number_is_a_value_error_like_any_other_mistake():
    for bad in ("1 s", None, 1j, True, [1.0, 2.0]):
        with pytest.raises(ValueError, match="^duration must be a finite number > 0"):
            cubic(bad)


# --------------------------------------------------------------------------------------
# joint trajectories and the Trajectory type


@pytest.mark.parametrize("law", ["trapezoidal", "cubic", "quintic"])
def test_joint_trajectory_synchronises_and_respects_limits(law):
    q_a = np.array([0.0, -1.0, 1.0, 0.5, -0.2, 0.0])
    q_b = np.array([1.5, -2.0, 0.2, 0.5, 1.0, -3.0])
    v_max = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
    a_max = np.array([2.0, 2.0, 2.0, 4.0, 4.0, 4.0])
    traj = joint_trajectory(q_a, q_b, v_max=v_max, a_max=a_max, law=law, dt=0.001)
    assert np.array_equal(traj.q[0], q_a)
    assert np.allclose(traj.q[-1], q_b, atol=1e-12)
    assert np.all(traj.qd[[0, -1]] == 0)
    peak_v = np.abs(traj.qd).max(axis=0)
    peak_a = np.abs(traj.qdd).max(axis=0)
    assert np.all(peak_v <= v_max * (1 + 1e-9)) and np.all(peak_a <= a_max * (1 + 1e-9))
    # one joint is at a limit (the duration is the shortest)
    assert np.max(np.maximum(peak_v / v_max, peak_a / a_max)) == pytest.approx(1.0, abs=2e-3)
    # synchronised: every moving joint is a scaled copy of one law
    scale = (traj.q - q_a) / np.where(q_b == q_a, 1.0, q_b - q_a)
    moving = q_b != q_a
    assert np.allclose(scale[:, moving], scale[:, [0]], atol=1e-12)
    assert np.all(traj.q[:, ~moving] == q_a[~moving])
    # speeds are the derivative of the positions
    assert np.allclose(central_difference(traj.q, traj.t)[1:-1], traj.qd[1:-1],
                       atol=2e-3 * v_max.max())


def test_joint_trajectory_with_a_duration_and_errors():
    traj = joint_trajectory([0, 0], [1.0, 2.0], duration=2.0, law="trapezoidal", dt=0.01)
    assert traj.duration == 2.0
    assert np.abs(traj.qd).max(axis=0) == pytest.approx([0.75, 1.5], rel=1e-9)
    hold = joint_trajectory([0.5, 0.5], [0.5, 0.5], duration=1.0)
    assert np.all(hold.q == 0.5) and np.all(hold.qd == 0)
    with pytest.raises(ValueError, match="too short for a_max"):
        joint_trajectory([0, 0], [1, 1], duration=1.0, a_max=1.0)
    with pytest.raises(ValueError, match="q_start equals q_goal"):
        joint_trajectory([0, 0], [0, 0], v_max=1.0)
    with pytest.raises(ValueError, match="law"):
        joint_trajectory([0, 0], [1, 1], duration=1.0, law="septic")
    with pytest.raises(ValueError, match="dt"):
        joint_trajectory([0, 0], [1, 1], duration=1.0, dt=0.0)
    with pytest.raises(ValueError, match="q_goal"):
        joint_trajectory([0, 0], [1, np.nan], duration=1.0)
    with pytest.raises(ValueError, match="same shape"):
        joint_trajectory([0, 0], [1, 1, 1], duration=1.0)
    with pytest.raises(ValueError, match="v_max"):
        joint_trajectory([0, 0], [1, 1], v_max=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="needs v_max and a_max"):
        joint_trajectory([0, 0], [1, 1], v_max=1.0, law="trapezoidal")


@pytest.mark.parametrize("j_max", [1e6, 100.0, 30.0])
def test_synchronised_trapezoid_against_ruckig(j_max):
    """Ruckig's time-optimal jerk-limited motion tends to the synchronised trapezoid: its
    duration is the trapezoid's plus a_max / j_max when the acceleration limit is reached."""
    ruckig = pytest.importorskip("ruckig")
    v_max = np.radians([180, 180, 180, 360, 360, 360])
    a_max = np.array([6.0, 6.0, 6.0, 12.0, 12.0, 12.0])
    q_a = np.array([0.0, -1.57, 1.2, -1.2, -1.57, 0.0])
    q_b = np.array([2.4, -1.0, 0.4, -2.2, -1.0, 2.5])
    ours = joint_trajectory(q_a, q_b, v_max=v_max, a_max=a_max, law="trapezoidal", dt=0.001)
    request = ruckig.InputParameter(6)
    request.current_position, request.target_position = list(q_a), list(q_b)
    request.max_velocity, request.max_acceleration = list(v_max), list(a_max)
    request.max_jerk = [j_max] * 6
    motion = ruckig.Trajectory(6)
    assert ruckig.Ruckig(6).calculate(request, motion) == ruckig.Result.Working
    assert motion.duration == pytest.approx(ours.duration + 6.0 / j_max, rel=1e-9)
    if j_max >= 1e6:          # and the pacing joint moves the same (the others need not:
        # Ruckig times every joint to end together but shapes each profile on its own)
        theirs = np.array([motion.at_time(t)[0] for t in ours.t])
        assert np.abs(theirs[:, 0] - ours.q[:, 0]).max() < 1e-4


def test_via_points_spline_against_scipy():
    from scipy.interpolate import CubicSpline

    rng = np.random.default_rng(12)
    times = np.array([0.0, 0.8, 1.5, 2.9, 3.4])
    Q = rng.uniform(-2, 2, (5, 3))
    traj = via_points(Q, times, dt=0.01)
    spline = CubicSpline(times, Q, bc_type="clamped")
    assert np.allclose(traj.q, spline(traj.t), atol=1e-12)
    assert np.allclose(traj.qd, spline(traj.t, 1), atol=1e-11)
    assert np.allclose(traj.qdd, spline(traj.t, 2), atol=1e-10)
    for k, tk in enumerate(times):          # every knot is on the grid, reached exactly
        i = int(np.argmin(np.abs(traj.t - tk)))
        assert traj.t[i] == pytest.approx(tk, abs=1e-12)
        assert np.allclose(traj.q[i], Q[k], atol=1e-12)


def test_via_points_stop_rests_at_every_point():
    times = np.array([1.0, 2.0, 4.0])
    traj = via_points([[0.0, 1.0], [1.0, 1.0], [-1.0, 0.0]], times, dt=0.1, method="stop")
    assert traj.t[0] == 1.0 and traj.t[-1] == 4.0
    for tk in times:
        i = int(np.argmin(np.abs(traj.t - tk)))
        assert np.all(np.abs(traj.qd[i]) < 1e-12) and np.all(np.abs(traj.qdd[i]) < 1e-12)
    with pytest.raises(ValueError, match="times"):
        via_points([[0.0], [1.0]], [0.0, 0.0])
    with pytest.raises(ValueError, match="method"):
        via_points([[0.0], [1.0]], [0.0, 1.0], method="bezier")
    with pytest.raises(ValueError, match="q_points"):
        via_points([[0.0]], [0.0])


def test_trajectory_validation():
    z = np.zeros((3, 2))
    with pytest.raises(ValueError, match="qd must have the shape of q"):
        Trajectory(t=[0, 1, 2], q=z, qd=np.zeros((3, 3)), qdd=z)
    with pytest.raises(ValueError, match="q must have shape"):
        Trajectory(t=[0, 1], q=z, qd=z, qdd=z)
    with pytest.raises(ValueError, match="qdd contains NaN"):
        Trajectory(t=[0, 1, 2], q=z, qd=z, qdd=np.full((3, 2), np.nan))
    with pytest.raises(ValueError, match="increase strictly"):
        Trajectory(t=[0, 2, 1], q=z, qd=z, qdd=z)
    with pytest.raises(ValueError, match="poses"):
        Trajectory(t=[0, 1, 2], q=z, qd=z, qdd=z, poses=np.zeros((2, 4, 4)))
    traj = Trajectory(t=[0, 1, 2], q=z, qd=z, qdd=z)
    with pytest.raises(ValueError):
        traj.q[0, 0] = 1.0                      # read-only


def test_csv_round_trip(tmp_path, robot, circle):
    rng = np.random.default_rng(3)
    traj = Trajectory(t=np.cumsum(rng.uniform(0.001, 0.01, 50)), q=rng.normal(size=(50, 6)),
                      qd=rng.normal(size=(50, 6)), qdd=rng.normal(size=(50, 6)))
    path = tmp_path / "a.csv"
    traj.save_csv(path)
    back = Trajectory.load_csv(path)
    for name in ("t", "q", "qd", "qdd"):
        assert np.array_equal(getattr(back, name), getattr(traj, name)), name
    assert back.poses is None
    with_poses, _ = follow_path_ur(robot, circle_three_phase(CENTER, R, V, 0.1,
                                                             orientation=R_WT), branch=2)
    with_poses.save_csv(path)
    header = path.read_text().splitlines()[0]
    assert header.startswith("t [s],q1 [rad]") and header.endswith("x [m],y [m],z [m],qw,qx,qy,qz")
    back = Trajectory.load_csv(path)
    assert np.array_equal(back.q, with_poses.q)
    assert np.allclose(back.poses, with_poses.poses, atol=1e-15)


def insert_line(text, index, line):
    lines = text.split("\n")
    return "\n".join(lines[:index] + [line] + lines[index:])


@pytest.mark.parametrize("damage, line, match", [
    (lambda text: text[: text.rindex(",")], 4, "expected 19 values, got 18"),
    (lambda text: insert_line(text, 2, "0.1,oops" + ",0" * 17), 3, "not a number"),
    (lambda text: "", 1, "empty file"),
    (lambda text: "time,q1\n" + text.split("\n", 1)[1], 1, "header"),
    (lambda text: text + "0.0" + ",0" * 18 + "\n", 5, "does not increase"),
    (lambda text: insert_line(text, 2, ""), 3, "empty line"),
    (lambda text: text + "9.0" + ",nan" * 18 + "\n", 5, "NaN"),
    (lambda text: text.split("\n", 1)[0] + "\n", 2, "no data rows"),
    (lambda text: text[:-2], 4, "truncated"),
])
def test_csv_errors_name_the_file_and_line(tmp_path, damage, line, match):
    traj = joint_trajectory(np.zeros(6), np.ones(6), duration=1.0, dt=0.5)
    path = tmp_path / "move.csv"
    traj.save_csv(path)
    path.write_text(damage(path.read_text()))
    with pytest.raises(ValueError, match=match) as info:
        Trajectory.load_csv(path)
    assert str(info.value).startswith(f"{path}, line {line}:")


# --------------------------------------------------------------------------------------
# Cartesian paths


def test_circle_has_the_reports_numbers(circle):
    assert len(circle) == 4399
    speed = circle.speed
    assert speed.max() <= V + 1e-12
    assert speed.max() == pytest.approx(V, abs=1e-12)
    assert f"{speed.max():.4f}" == "0.0500"
    assert np.allclose(speed, circle.sd, atol=1e-15)
    assert np.allclose(np.diff(circle.t), DT)
    assert circle.t[-1] < 3.5 * np.pi * R / V <= circle.t[-1] + DT
    d = circle.position - CENTER
    assert np.allclose(np.linalg.norm(d, axis=1), R, atol=1e-15)
    assert np.all(d[:, 1] == 0)                             # in the (X, Z) plane
    assert np.allclose(circle.position[0], CENTER + [0, 0, R], atol=1e-15)
    assert circle.s[-1] <= 2 * np.pi * R and circle.s[-1] == pytest.approx(2 * np.pi * R,
                                                                          abs=1e-7)


def test_circle_derivatives_agree_with_finite_differences(circle):
    t = circle.t
    inner = slice(1, -1)
    jumps = np.min(np.abs(t[:, None] - circle.law.switch_times[None, :]), axis=1) < 2 * DT
    fd = central_difference(circle.position, t)
    assert np.allclose(fd[inner][~jumps[inner]], circle.velocity[inner][~jumps[inner]],
                       rtol=0, atol=DT**2 * V**3 / R**2)
    assert np.allclose(fd[inner], circle.velocity[inner], atol=DT * V**2 / (np.pi * R))
    acc = central_difference(circle.velocity, t)
    assert np.allclose(acc[inner][~jumps[inner]], circle.acceleration[inner][~jumps[inner]],
                       atol=1e-6)
    # centripetal part: the normal acceleration is sd^2 / R
    normal = -(circle.position - CENTER) / R
    assert np.allclose(np.sum(circle.acceleration * normal, axis=1), circle.sd**2 / R,
                       atol=1e-15)


@pytest.mark.parametrize("plane, axes", [("xy", (0, 1, 2)), ("yz", (1, 2, 0))])
def test_circle_in_other_planes(plane, axes):
    path = circle_three_phase([0.1, 0.2, 0.3], 0.05, 0.1, 0.01, plane=plane)
    i, j, k = axes
    assert np.all(path.position[:, k] == [0.1, 0.2, 0.3][k])
    assert path.position[0, j] == pytest.approx([0.1, 0.2, 0.3][j] + 0.05)
    assert path.velocity[1, i] < 0


@pytest.mark.parametrize("call, match", [
    (lambda: circle_three_phase([0, 0], 0.1, 0.05), "center"),
    (lambda: circle_three_phase([0, 0, np.nan], 0.1, 0.05), "center"),
    (lambda: circle_three_phase([0, 0, 0], -0.1, 0.05), "radius"),
    (lambda: circle_three_phase([0, 0, 0], 0.1, 0.0), "speed"),
    (lambda: circle_three_phase([0, 0, 0], 0.1, 0.05, dt=0), "dt"),
    (lambda: circle_three_phase([0, 0, 0], 0.1, 0.05, plane="xx"), "plane"),
    (lambda: circle_three_phase([0, 0, 0], 0.1, 0.05, orientation=np.eye(2)), "orientation"),
    (lambda: line_slerp(np.eye(4), np.eye(4)), "duration"),
    (lambda: line_slerp(np.eye(4), np.eye(4), law=quintic(1.0, 2.0)), "from 0 to 1"),
    (lambda: screw_path(np.eye(4), 2 * np.eye(4), duration=1.0), "X_B"),
])
def test_path_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def angular_velocity_from_quaternions(q, t):
    """omega = 2 q_dot q^* (world frame), by central differences."""
    qd = central_difference(q, t)
    return 2 * quaternion_product(qd, quaternion_conjugate(q))[:, 1:]


X_A = transform_from(rot_z(0.3) @ rot_x(-0.4), [0.3, -0.2, 0.25])
X_B = transform_from(rot_y(1.2) @ rot_z(-0.8), [-0.1, -0.35, 0.4])


@pytest.mark.parametrize("make", [line_slerp, screw_path])
def test_line_and_screw_paths_end_and_derivatives(make):
    path = make(X_A, X_B, duration=2.0, dt=0.001)
    assert np.allclose(path.poses[0], X_A, atol=1e-12)
    assert np.allclose(path.poses[-1], X_B, atol=1e-12)
    t = path.t
    inner = slice(1, -1)
    assert np.allclose(central_difference(path.position, t)[inner], path.velocity[inner],
                       atol=1e-5)
    assert np.allclose(central_difference(path.velocity, t)[inner],
                       path.acceleration[inner], atol=1e-4)
    q = path.orientation * np.sign(path.orientation @ path.orientation[0])[:, None]
    assert np.allclose(angular_velocity_from_quaternions(q, t)[inner],
                       path.angular_velocity[inner], atol=1e-5)


def test_line_is_straight_and_screw_is_not():
    line = line_slerp(X_A, X_B, duration=1.0, dt=0.01)
    screw = screw_path(X_A, X_B, duration=1.0, dt=0.01)
    chord = X_B[:3, 3] - X_A[:3, 3]

    def off(p):
        return np.linalg.norm(np.cross(p - X_A[:3, 3], chord / np.linalg.norm(chord)), axis=1)

    assert off(line.position).max() < 1e-15
    assert off(screw.position).max() > 0.02
    # same orientations (both rotate about the same axis at the same rate)
    assert np.allclose(np.abs(np.sum(line.orientation * screw.orientation, axis=1)), 1.0,
                       atol=1e-12)
    # for a pure translation the two coincide
    X_C = transform_from(X_A[:3, :3], [0.0, 0.1, 0.5])
    assert np.allclose(line_slerp(X_A, X_C, duration=1.0, dt=0.1).position,
                       screw_path(X_A, X_C, duration=1.0, dt=0.1).position, atol=1e-15)


def test_screw_path_against_pytransform3d():
    pt = pytest.importorskip("pytransform3d.transformations")
    path = screw_path(X_A, X_B, law=quintic(1.0), dt=0.05)
    dq_a = pt.dual_quaternion_from_transform(X_A)
    dq_b = pt.dual_quaternion_from_transform(X_B)
    for s, X in zip(path.s, path.poses, strict=True):
        theirs = pt.transform_from_dual_quaternion(pt.dual_quaternion_sclerp(dq_a, dq_b, s))
        assert np.allclose(X, theirs, atol=1e-12)


def test_cartesian_path_validation():
    with pytest.raises(ValueError, match="velocity"):
        CartesianPath(t=[0, 1], position=np.zeros((2, 3)), velocity=np.zeros((3, 3)),
                      acceleration=np.zeros((2, 3)))
    path = CartesianPath(t=[0, 1], position=np.zeros((2, 3)), velocity=np.zeros((2, 3)),
                         acceleration=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="no orientation"):
        _ = path.poses


# --------------------------------------------------------------------------------------
# following



@pytest.fixture(scope="module")
def followed(robot, circle):
    return follow_path_ur(robot, circle, branch=("left", "down", "noflip"))


def test_closed_form_following_reproduces_every_pose(robot, circle, followed):
    traj, report = followed
    X = robot.fk(traj.q)
    assert np.abs(X[:, :3, 3] - circle.position).max() <= 1e-9
    assert np.abs(X[:, :3, :3] - R_WT).max() <= 1e-9
    assert report.position_error.max() <= 1e-9
    assert report.switches == [] and np.all(report.branch == 2)


def test_closed_form_following_never_jumps_more_than_the_path_step(followed):
    traj, report = followed
    step = np.abs(np.diff(traj.q, axis=0))
    speed = np.maximum(np.abs(traj.qd[:-1]), np.abs(traj.qd[1:]))
    assert np.all(step <= speed * np.diff(traj.t)[:, None] * 1.01 + 1e-12)
    assert report.max_step.max() < 2e-3


def test_joint_speeds_agree_with_the_derivative_of_q(circle, followed):
    traj, _ = followed
    error = np.abs(central_difference(traj.q, traj.t) - traj.qd).max(axis=1)
    # O(dt^2) away from the switches of the law, O(dt * jump of s_ddot) next to them
    near = np.min(np.abs(traj.t[:, None] - circle.law.switch_times[None, :]), axis=1) < 2 * DT
    assert error[1:-1][~near[1:-1]].max() < 1e-6
    assert error[1:-1].max() < 1e-4
    assert np.allclose(traj.qdd, central_difference(traj.qd, traj.t))


def test_closed_form_following_is_one_of_ur_analytic_iks_solutions(robot, circle, followed):
    uaik = pytest.importorskip("ur_analytic_ik")
    traj, _ = followed
    for k in range(0, len(circle), 200):
        with quiet_stdout():
            theirs = np.array(uaik.ur3.inverse_kinematics(circle.poses[k]))
        diff = np.abs(np.angle(np.exp(1j * (theirs - traj.q[k]))))
        assert diff.max(axis=1).min() < 1e-9, k


def test_chapter_circle_margins(followed):
    _, report = followed
    m = {k: v.min() for k, v in report.margins.items()}
    assert m["wrist"] > 0.5 and m["elbow"] > 0.5 and m["reach"] > 0.05 and m["shoulder"] > 0.1


def test_margins_against_forward_kinematics(robot):
    q = np.random.default_rng(5).uniform(-np.pi, np.pi, (200, 6))
    m = ur_singularity_margins(robot, q)
    frames = robot.fk(q, all_frames=True)
    shoulder, wrist1, wrist_centre = frames[:, 1, :3, 3], frames[:, 3, :3, 3], frames[:, 5, :3, 3]
    reach = 0.24365 + 0.21325 - np.linalg.norm(wrist1 - shoulder, axis=1)
    assert np.allclose(m["reach"], reach, atol=1e-14)
    assert np.allclose(m["shoulder"], np.hypot(*wrist_centre[:, :2].T) - 0.11235, atol=1e-14)
    assert np.allclose(m["wrist"], np.abs(np.sin(q[:, 4])))
    # the report's modified-DH table is refused (the formulas read a standard one); a
    # calibrated UR, whose table has far common normals, gets its nearest exact UR's
    with pytest.raises(ValueError, match="robot: .* modified DH"):
        ur_singularity_margins(ur3_mdh(), q)
    from dqlab.ur.calibration import robot_from_joint_origins
    S, previous = [], None                                     # joint origins, as URDF
    for k, link in enumerate(robot.links):
        T = np.eye(4)
        if previous is not None:
            T[:3, :3], T[0, 3] = rot_x(previous.alpha), previous.a
        M = np.eye(4)
        M[:3, :3] = rot_y(1e-3 * (k in (2, 3)))                # axes 3, 4 tilted by 1 mrad
        M[2, 3] = link.d
        S.append(T @ M)
        previous = link
    calibrated = robot_from_joint_origins(np.array(S), name="UR3 (tilted)")
    assert abs(calibrated.links[1].d) > 1.0                   # far common normals
    exact, tilted = ur_singularity_margins(robot, q), ur_singularity_margins(calibrated, q)
    for name in exact:
        assert np.abs(tilted[name] - exact[name]).max() < 2e-3, name


def test_tracking_unwraps_through_pi(robot):
    q_path = np.linspace([3.0, -1.0, 1.2, -1.5, 1.0, 3.0], [3.6, -1.2, 1.0, -1.3, 1.2, 3.9], 200)
    q, rows, switches = track_branches(ur(robot, robot.fk(q_path)), q_start=q_path[0])
    assert np.allclose(q, q_path, atol=1e-9) and switches == []


def test_tracking_through_the_wrist_singularity_switches_rows_continuously(robot):
    q_path = np.linspace([0.4, -1.3, 1.4, -1.2, 0.25, 0.3], [0.5, -1.2, 1.3, -1.0, -0.25, 0.6],
                         101)[np.r_[0:50, 51:101]]              # theta5 = 0 is skipped
    res = ur(robot, robot.fk(q_path))
    q, rows, switches = track_branches(res, q_start=q_path[0])
    assert np.allclose(q, q_path, atol=1e-8)
    assert [s.kind for s in switches] == ["singularity"]
    assert switches[0].index == 50 and rows[49] % 2 == 0 and rows[50] % 2 == 1


def test_tracking_reports_a_jump(robot):
    q1 = np.array([0.4, -1.3, 1.4, -1.2, 1.0, 0.3])
    q2 = np.array([0.4, -1.3, 1.4, -1.2, 1.0, 2.3])           # joint 6 turns by 2 rad
    q_path = np.r_[np.linspace(q1, q1 + 0.01, 5), np.linspace(q2, q2 + 0.01, 5)]
    _, _, switches = track_branches(ur(robot, robot.fk(q_path)), q_start=q1)
    assert [(s.index, s.kind) for s in switches] == [(5, "jump")]
    assert switches[0].step == pytest.approx(2.0 - 0.01, abs=1e-9)


def test_following_errors(robot, circle):
    with pytest.raises(ValueError, match="no orientation"):
        follow_path_ur(robot, circle_three_phase(CENTER, R, V, 0.5))
    with pytest.raises(ValueError, match="point 0 .* no IK solution"):
        follow_path_ur(robot, circle_three_phase([1.0, 0, 0], R, V, 0.5, orientation=R_WT))
    with pytest.raises(ValueError, match="branch"):
        follow_path_ur(robot, circle, branch=9)
    with pytest.raises(ValueError, match="branch"):
        follow_path_ur(robot, circle, branch=("left", "sideways", "noflip"))
    with pytest.raises(TypeError, match="CartesianPath"):
        follow_path_ur(robot, circle.poses)
    with pytest.raises(ValueError, match="max_step"):
        follow_path_ur(robot, circle, max_step=0)
    with pytest.raises(ValueError, match="q"):
        follow_path_ur(robot, circle, q_start=[0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match="not reached"):
        follow_path_numerical(robot, circle_three_phase([1.0, 0, 0], R, V, 0.5), np.zeros(6))


def test_numerical_following_like_the_report(robot, followed):
    traj_cf, _ = followed
    path = circle_three_phase(CENTER, R, V, 0.05)
    traj, report = follow_path_numerical(robot, path, traj_cf.q[0])
    assert np.abs(robot.fk(traj.q)[:, :3, 3] - path.position).max() <= 1e-10
    assert report.position_error.max() <= 1e-10
    # J_v q_dot reproduces the tool velocity, and q_dot agrees with the derivative of q to
    # the order of the path step
    J_v = robot.jacobian(traj.q)[:, :3, :]
    assert np.allclose((J_v @ traj.qd[..., None])[..., 0], path.velocity, atol=1e-12)
    fd = central_difference(traj.q, traj.t)
    assert np.abs(fd - traj.qd)[1:-1].max() < 0.05 * np.abs(traj.qd).max()


def test_joint_velocities():
    rng = np.random.default_rng(8)
    J = rng.normal(size=(10, 6, 6))
    x = rng.normal(size=(10, 6))
    assert np.allclose(joint_velocities(J, x), np.linalg.solve(J, x[..., None])[..., 0])
    Jv = J[:, :3]
    assert np.allclose(joint_velocities(Jv, x[:, :3]),
                       (np.linalg.pinv(Jv) @ x[:, :3, None])[..., 0])
    lam = 0.1
    U, S, Vt = np.linalg.svd(Jv)
    dls = np.einsum("bji,bj,bj->bi", Vt[:, :3], S / (S**2 + lam**2),
                    np.einsum("bji,bj->bi", U, x[:, :3]))
    assert np.allclose(joint_velocities(Jv, x[:, :3], damping=lam), dls)
    singular = np.array([[1.0, 0.0], [0.0, 0.0]])
    assert np.allclose(joint_velocities(singular, [1.0, 1.0]), [1.0, 0.0])
    bound = joint_velocities(np.diag([1.0, 1e-9]), [0.0, 1.0], damping=lam)
    assert np.linalg.norm(bound) <= 1 / (2 * lam)
    with pytest.raises(ValueError, match="twist"):
        joint_velocities(J, x[:, :3])
    with pytest.raises(ValueError, match="damping"):
        joint_velocities(J, x, damping=-1.0)


@settings(max_examples=40, deadline=None)
@given(f1=st.floats(0.05, 0.9), f2=st.floats(0.0, 0.9), D=st.floats(0.01, 5.0),
       V=st.floats(0.01, 2.0))
def test_three_phase_with_any_fractions(f1, f2, D, V):
    if f1 + f2 > 0.95:
        f2 = 0.95 - f1
    f = (f1, f2, 1.0 - f1 - f2)
    law = three_phase(D, V, f)
    assert law.duration == pytest.approx((2 * f[0] + f[1] + 2 * f[2]) * D / V, rel=1e-12)
    assert law.peak_speed == pytest.approx(V, rel=1e-12)
    assert law.distance == pytest.approx(D, rel=1e-12)
    s = law.position(law.breaks)
    assert s[0] == 0.0 and s[-1] == pytest.approx(D, rel=1e-12)
    assert s[1] == pytest.approx(f[0] * D, rel=1e-12)


def pose_path(robot, q_path, dt=0.01):
    """A CartesianPath through the forward kinematics of a joint path (speeds unused)."""
    from dqlab import quaternion_from_matrix

    X = robot.fk(q_path)
    n = len(q_path)
    return CartesianPath(t=np.arange(n) * dt, position=X[:, :3, 3], velocity=np.zeros((n, 3)),
                         acceleration=np.zeros((n, 3)),
                         orientation=quaternion_from_matrix(X[:, :3, :3]),
                         angular_velocity=np.zeros((n, 3)))


def test_tracking_starts_at_the_equivalent_nearest_q_start(robot):
    q_path = np.linspace([0.4, -1.3, 1.4, -1.2, 1.0, -2.5], [0.5, -1.2, 1.3, -1.0, 1.2, -2.2],
                         30)
    q_start = q_path[0] + [0, 0, 0, 0, 0, 2 * np.pi]          # joint 6 one turn further
    traj, report = follow_path_ur(robot, pose_path(robot, q_path), q_start=q_start)
    assert np.allclose(traj.q, q_path + [0, 0, 0, 0, 0, 2 * np.pi], atol=1e-9)
    assert report.switches == []


def test_following_refuses_to_leave_the_joint_limits(robot):
    # (on joint 5: the UR3's wrist 3 turns without limit)
    q_path = np.linspace([0.4, -1.3, 1.4, -1.2, 6.1, 1.0], [0.4, -1.3, 1.4, -1.2, 6.5, 1.0], 30)
    with pytest.raises(ValueError, match="joint 5 .* limits|limits: joint 5"):
        follow_path_ur(robot, pose_path(robot, q_path), q_start=q_path[0])


# --------------------------------------------------------------------------------------
# overflow, underflow and the first instant


def test_time_grid_keeps_the_first_instant_however_short_the_motion():
    assert time_grid(1e-12, 0.005).tolist() == [0.0, 1e-12]
    assert time_grid(0.0, 0.005).tolist() == [0.0]
    traj = joint_trajectory([0.0, 0.0], [1.0, -1.0], duration=2.0, dt=1e9)
    assert traj.t.tolist() == [0.0, 2.0]
    assert traj.q.tolist() == [[0.0, 0.0], [1.0, -1.0]]


def test_via_points_a_picosecond_apart_keep_every_knot():
    traj = via_points([[0.0], [1e-12], [1.0]], [0.0, 1e-12, 1.0], dt=0.1)
    assert traj.t[0] == 0.0 and traj.t[1] == 1e-12 and traj.t[-1] == 1.0
    assert traj.q[[0, 1, -1], 0].tolist() == [0.0, 1e-12, 1.0]


def test_time_grid_refuses_more_samples_than_it_can_hold():
    with pytest.raises(ValueError, match="too large"):
        time_grid(1e200, 0.005)


@pytest.mark.parametrize("T", [1e-100, 1e-3, 1.0, 1e70, 1e100, 1e150])
def test_polynomial_laws_of_any_duration_are_exact(T):
    """No power of the duration in the coefficients: no overflow, no underflow."""
    for law, c_v, c_a in ((cubic(T, 2.0), 1.5, 6.0), (quintic(T, 2.0), 1.875, 10 / 3**0.5)):
        assert law.distance == pytest.approx(2.0, rel=1e-15)
        assert float(law.position(T / 2)) == pytest.approx(1.0, rel=1e-15)
        assert law.peak_speed == pytest.approx(c_v * 2.0 / T, rel=1e-12)
        assert law.peak_acceleration == pytest.approx(c_a * 2.0 / T / T, rel=1e-12)
        assert np.all(np.isfinite(law(np.linspace(0.0, T, 11))))


def test_a_law_whose_derivatives_overflow_is_refused():
    with pytest.raises(ValueError, match="overflows"):
        cubic(1e-200)
    with pytest.raises(ValueError, match="overflows"):
        quintic(1.0, 1e307)
    with pytest.raises(ValueError, match="too large"):
        quintic(1.0, 1e308)


def test_a_trapezoid_with_an_unrepresentable_phase_names_its_cause():
    with pytest.raises(ValueError, match="accel_fraction = 1e-300"):
        trapezoidal(1.0, duration=1.0, accel_fraction=1e-300)
    law = trapezoidal(1.0, duration=1.0, a_max=1e12)     # a tiny ramp, well computed
    assert law.switch_times[0] == pytest.approx(1e-12, rel=1e-6)
    assert law.peak_acceleration == pytest.approx(1e12, rel=1e-9)


@pytest.mark.parametrize("scale", [1e-160, 1.0, 1e160])
def test_joint_velocities_do_not_overflow_or_underflow(scale):
    x = np.array([0.3, -0.2, 0.1, 0.05, 0.0, -0.4])
    J = ur3().jacobian(np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2]))
    reference = np.linalg.solve(J, x)
    assert np.allclose(joint_velocities(scale * J, x) * scale, reference, rtol=1e-10)
    np.testing.assert_allclose(joint_velocities(scale * np.eye(6), x), x / scale, rtol=1e-14)


def test_joint_velocities_with_damping_far_above_the_singular_values():
    J = np.diag([1e-3, 2e-3])
    x = np.array([1.0, 1.0])
    lam = 1e120                                   # lambda^2 / sigma^2 beyond 1e200
    np.testing.assert_allclose(joint_velocities(J, x, damping=lam), J.T @ x / lam**2,
                               rtol=1e-12)


def test_joint_velocities_name_a_one_dimensional_j():
    with pytest.raises(ValueError, match="^J must have shape"):
        joint_velocities(np.ones(6), np.ones(6))


def test_track_branches_refuses_a_short_t_and_a_float_branch(robot):
    q_path = np.linspace([0.4, -1.3, 1.4, -1.2, 1.0, -2.5], [0.5, -1.2, 1.3, -1.0, 1.2, -2.2], 5)
    result = ur(robot, robot.fk(q_path))
    with pytest.raises(ValueError, match="^t must have shape \\(5,\\)"):
        track_branches(result, t=[0.0, 0.1])
    for branch in (1.0, True, "up"):
        with pytest.raises(ValueError, match="^branch must be"):
            track_branches(result, branch=branch)
    with pytest.raises(TypeError, match="^result must be a IKResult"):
        track_branches(q_path)


def test_paths_need_their_position_velocity_and_acceleration():
    with pytest.raises(ValueError, match="^velocity is required"):
        CartesianPath(t=[0.0], position=[[0.0, 0, 0]], velocity=None,
                      acceleration=[[0.0, 0, 0]])


def test_every_function_that_takes_a_robot_refuses_none(robot):
    path = line_slerp(transform_from(rot_x(np.pi / 2), [0.0, -0.3, 0.3]),
                      transform_from(rot_x(np.pi / 2), [0.05, -0.3, 0.3]), duration=0.1,
                      dt=0.05)
    for call in (lambda: follow_path_ur(None, path),
                 lambda: ur_singularity_margins(None, np.zeros(6)),
                 lambda: follow_path_numerical(None, path, np.zeros(6))):
        with pytest.raises(TypeError, match="^robot must be a Robot, got None"):
            call()


def test_a_csv_file_that_is_not_utf8_is_refused_naming_the_file_and_line(tmp_path):
    path = tmp_path / "traj.csv"
    joint_trajectory([0.0], [1.0], duration=1.0, dt=0.5).save_csv(path)
    data = path.read_bytes().split(b"\n")
    data[2] = data[2][:3] + b"\xff" + data[2][3:]
    path.write_bytes(b"\n".join(data))
    with pytest.raises(ValueError, match=r"traj\.csv, line 3: byte 0xff at column 4 is not "
                                         r"UTF-8"):
        Trajectory.load_csv(path)
    with pytest.raises(TypeError, match="^path must be a file path"):
        Trajectory.load_csv(None)


@settings(max_examples=30, deadline=None)
@given(L=st.floats(0.01, 1.0), V=st.floats(0.01, 1.0), A=st.floats(0.05, 5.0))
def test_a_line_run_at_a_tool_speed_stays_within_it(L, V, A):
    X_A = transform_from(rot_x(0.3), [0.1, -0.2, 0.3])
    X_B = transform_from(rot_x(0.3) @ rot_z(0.5), X_A[:3, 3] + L * np.array([0.6, 0.0, 0.8]))
    path = line_slerp(X_A, X_B, speed=V, acceleration=A, dt=0.002)
    t = np.linspace(0.0, path.law.duration, 4001)
    s, sd, sdd = path.law(t)
    assert np.max(np.abs(sd)) * L <= V * (1 + 1e-9)
    assert np.max(np.abs(sdd)) * L <= A * (1 + 1e-9)
    T = L / V + V / A if L > V * V / A else 2 * np.sqrt(L / A)      # the shortest motion
    assert path.law.duration == pytest.approx(T, rel=1e-12)
    assert np.allclose(path.position[-1], X_B[:3, 3], atol=1e-15)


def test_a_line_takes_one_timing():
    X_B = transform_from(np.eye(3), [0.3, 0.0, 0.0])
    for kwargs in ({"duration": 1.0, "law": quintic(1.0)}, {"duration": 1.0, "speed": 0.1,
                                                             "acceleration": 1.0},
                   {"speed": 0.1}):
        with pytest.raises(ValueError, match="give"):
            line_slerp(np.eye(4), X_B, **kwargs)
    with pytest.raises(ValueError, match="^speed: the line has length 0"):
        line_slerp(np.eye(4), transform_from(rot_z(1.0), [0.0, 0.0, 0.0]), speed=0.1,
                   acceleration=1.0)


def test_a_line_through_the_wrist_singularity_is_named():
    """A straight line that takes the UR5e's wrist through |sin q5| < 1e-3: the report names
    the wrist singularity where it happens, with the joint speed it asks for (far beyond the
    rated 3.14 rad/s, which a program's speed check would refuse later), the branch switches
    there say so, and the summary prints it; a path away from it has no pass."""
    from dqlab.models import ur5e
    from dqlab.trajectory import SingularPass, line_slerp

    robot = ur5e().with_tool(z=0.15)
    q0 = np.array([0.0, -1.6, 1.6, -1.571, 0.05, 0.0])
    q1 = q0.copy()
    q1[4] = -0.05
    path = line_slerp(robot.fk(q0), robot.fk(q1), speed=0.25, acceleration=0.5, dt=0.008)
    traj, report = follow_path_ur(robot, path, q_start=q0)
    [wrist] = [p for p in report.singularities if p.kind == "wrist"]
    assert isinstance(wrist, SingularPass) and wrist.measure < 1e-3
    assert wrist.speed > 10 * np.pi and wrist.joint in (4, 6)
    assert wrist.speed == pytest.approx(np.abs(traj.qd[wrist.first:wrist.last + 1]).max())
    assert report.switches and all("wrist singularity" in s.reason for s in report.switches)
    assert "passes the wrist singularity" in report.summary()
    # the circle of chapter 11 keeps away from every singularity
    circle = circle_three_phase(CENTER, R, V, 0.1, orientation=rot_x(np.pi / 2))
    _, calm = follow_path_ur(ur3(), circle, branch=("right", "up", "noflip"))
    assert calm.singularities == [] and "singularity" not in calm.summary()
    with pytest.raises(ValueError, match="near_tol"):
        follow_path_ur(robot, path, q_start=q0, near_tol=-1.0)
