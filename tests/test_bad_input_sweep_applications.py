"""Part III's bad-input sweep: every public callable of dqlab.trajectory, dqlab.identify,
dqlab.pick_place (and its animation in dqlab.viz), dqlab.sim (but the UR back end),
dqlab.reachability and dqlab.dask_arrays, every argument, every kind of bad value.

As in ``tests/test_bad_input_sweep.py`` for the core: for each callable a good call is
given; each argument is then replaced, one at a time, by every bad value of its kind
(``tests/_sweep.py``: arrays and numbers get NaN, inf, None, text, complex numbers, the wrong
shape, a ragged list, an empty batch, huge, tiny and far magnitudes, and a single number also
a boolean, a number as text and a numpy number; integers also fractions and integers beyond
64 bits; objects get None, a number, text, a list and a boolean; a file to write gets None,
a number, a list, a directory and a missing folder; a file to read also an empty, binary,
truncated, huge or deeply nested file). The call must raise ValueError or TypeError whose
message names the argument (for magnitudes: or says the result overflows or is too large;
for a path: an error naming the file), or return a correct result: for an empty batch an
empty one, for huge or tiny magnitudes finite numbers, for an argument of any shape finite
numbers, for an optional argument given None its default. Anything else fails; the
session's summary counts the outcomes per module.
"""

from xml.etree import ElementTree

import numpy as np
import pytest
from _sweep import A, F, Int, Name, O, P, Registry, S, T, sweep_test
from _sweep import Any as Any_

from dqlab import identify, ik
from dqlab import pick_place as pp
from dqlab.models import desk_arm, ur3
from dqlab.reachability import (
    ReachabilityMap,
    check_ik_options,
    pose_dexterity,
    reachability_statistics,
    super_fibonacci_quaternions,
)
from dqlab.rotations import rot_x, rot_z
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
from dqlab.transforms import transform_from

# an identification asked for with a tiny max_condition or rank_tol warns, as it should
pytestmark = pytest.mark.filterwarnings("ignore::dqlab.identify.IllConditionedWarning")

UR3 = ur3()
DESK = desk_arm()
Q6 = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
X_A = transform_from(rot_x(np.pi / 2), [0.0, -0.25, 0.35])
X_B = transform_from(rot_x(np.pi / 2) @ rot_z(0.3), [0.05, -0.3, 0.3])
LAW = quintic(1.0)
TRAJ = joint_trajectory(Q6, Q6 + 0.1, duration=0.2, dt=0.05)
PATH = line_slerp(X_A, X_B, duration=0.2, dt=0.05)
IK_PATH = ik.ur(UR3, PATH.poses)
LAB_ROWS = [[0, 170, 80, 0, 0], [0, 170, 30, 1, 0], [0, 170, 80, 1, 0], [0, -170, 85, 1, 180],
            [0, -170, 35, 0, 180]]
TASK = pp.task_from_lab(LAB_ROWS)
PLAN = pp.plan_pick_place(DESK, TASK, dt=0.1)
Q_DESK = np.array([[0.1, 0.9, -1.9], [0.4, 1.1, -2.0], [-0.3, 1.0, -1.7], [0.2, 1.3, -2.3],
                   [0.0, 0.8, -1.5], [-0.5, 1.2, -2.1], [0.6, 1.0, -1.6], [0.3, 0.7, -1.4]])
A_FIT = np.column_stack([np.ones(6), np.arange(6.0), np.arange(6.0) ** 2])
B_FIT = np.array([1.0, 2.1, 4.9, 10.2, 16.8, 26.1])
Q_LAB = np.radians([[90, 90, 0], [90, 51, 65], [90, 42, 21], [90, 90, 45], [30, 60, 20]])
P_LAB = np.array([[229, 0, 179], [226, 0, 0], [325, 0, 73], [182, 0, 64],
                  [140, 240, 110]]) / 1000
QUATS = super_fibonacci_quaternions(4)
GRID = np.array([[0.0, -0.35, 0.25], [0.9, 0.0, 0.2]])
FIT = identify.fit_linear(A_FIT, B_FIT, names=["a", "b", "c"])


Any = Any_
CASES = Registry()


def case(module, title, call, check=None, writes=None, setup=None, **args):
    CASES.add(module, title, call, check=check, writes=writes, **args).setup = setup


# -- dqlab.trajectory --------------------------------------------------------------------

M = "trajectory"
case(M, "cubic", cubic, duration=S(1.5), distance=S(0.8))
case(M, "quintic", quintic, duration=S(1.5), distance=S(-0.8))
case(M, "trapezoidal(v_max, a_max)", trapezoidal, distance=S(0.9), v_max=S(0.5),
     a_max=S(2.0))
case(M, "trapezoidal(duration, accel_fraction)", trapezoidal, distance=S(0.9),
     duration=S(2.0), accel_fraction=S(0.25, none_ok=True))
case(M, "trapezoidal(duration, a_max)", lambda **kw: trapezoidal(0.9, **kw), duration=S(2.0),
     a_max=S(2.0, none_ok=True))
case(M, "trapezoidal(duration, v_max)", lambda **kw: trapezoidal(0.9, **kw), duration=S(2.0),
     v_max=S(0.6, none_ok=True))
case(M, "three_phase", three_phase, distance=S(0.6), speed=S(0.05),
     fractions=A([0.25, 0.25, 0.5]))
case(M, "time_grid", time_grid, duration=S(0.02), dt=S(0.008))
case(M, "TimeLaw", TimeLaw, breaks=A([0.0, 1.0]), coefficients=A([[0, 0, 3, -2, 0, 0]]))
for method in ("position", "speed", "acceleration", "jerk"):
    case(M, f"TimeLaw.{method}", getattr(LAW, method), t=Any([0.0, 0.3, 0.6, 1.0, 1.2]))
case(M, "TimeLaw.sample", LAW.sample, dt=S(0.25))
case(M, "Trajectory", Trajectory, t=A(TRAJ.t), q=A(TRAJ.q), qd=A(TRAJ.qd), qdd=A(TRAJ.qdd),
     poses=A(UR3.fk(TRAJ.q), none_ok=True))
case(M, "Trajectory.save_csv", lambda path: TRAJ.save_csv(path), path=P("traj.csv"),
     writes="path", check=lambda _, kw: _reads_back(kw["path"], TRAJ))
case(M, "Trajectory.load_csv", Trajectory.load_csv, path=F("traj.csv"),
     setup=lambda folder: TRAJ.save_csv(folder / "traj.csv"))
case(M, "joint_trajectory(limits)", joint_trajectory, q_start=A(Q6), q_goal=A(Q6 + 0.5),
     v_max=A([1.0] * 6), a_max=S(2.0), law=O("trapezoidal"), dt=S(0.05))
case(M, "joint_trajectory(duration)", joint_trajectory, q_start=A(Q6), q_goal=A(Q6 - 0.5),
     duration=S(1.5), law=O("cubic"), dt=S(0.05))
case(M, "via_points", via_points, q_points=Any([[0.0, 1.0], [1.0, 0.5], [0.5, 0.0]]),
     times=A([0.0, 1.0, 2.5]), dt=S(0.1), method=O("spline"))
case(M, "CartesianPath", CartesianPath, t=A(PATH.t), position=A(PATH.position),
     velocity=A(PATH.velocity), acceleration=A(PATH.acceleration),
     orientation=A(PATH.orientation, none_ok=True),
     angular_velocity=A(PATH.angular_velocity, none_ok=True))
case(M, "CartesianPath.with_orientation", PATH.with_orientation, rotation=A(rot_x(0.4)))
case(M, "line_slerp", line_slerp, X_A=A(X_A), X_B=A(X_B), duration=S(0.5), dt=S(0.1))
case(M, "line_slerp(law)", line_slerp, X_A=A(X_A), X_B=A(X_B), law=O(LAW), dt=S(0.1))
case(M, "line_slerp(speed)", line_slerp, X_A=A(X_A), X_B=A(X_B), speed=S(0.2),
     acceleration=S(1.0), dt=S(0.1))
case(M, "screw_path", screw_path, X_A=A(X_A), X_B=A(X_B), duration=S(0.5), dt=S(0.1))
case(M, "circle_three_phase", circle_three_phase, center=A([0.0, -0.35, 0.25]),
     radius=S(0.1), speed=S(0.5), dt=S(0.1), plane=O("xz"), fractions=A([0.25, 0.25, 0.5]),
     orientation=A(rot_x(np.pi / 2), none_ok=True))
case(M, "joint_velocities", joint_velocities, J=Any(UR3.jacobian(Q6)),
     twist=A([0.1, 0.0, 0.0, 0.0, 0.0, 0.2]), damping=S(0.01))
case(M, "ur_singularity_margins", ur_singularity_margins, robot=O(UR3), q=A(Q6))
case(M, "track_branches", track_branches, result=O(IK_PATH), q_start=A(Q6, none_ok=True),
     branch=O(4, none_ok=True), max_step=S(0.5, inf_ok=True), t=A(PATH.t, none_ok=True))
case(M, "follow_path_ur", follow_path_ur, robot=O(UR3), path=O(PATH),
     q_start=A(IK_PATH.solutions[0, 4], none_ok=True), branch=O(4, none_ok=True),
     max_step=S(0.5, inf_ok=True), damping=S(0.0), tol=S(1e-9))
case(M, "follow_path_numerical", follow_path_numerical, robot=O(UR3), path=O(PATH),
     q_start=A(IK_PATH.solutions[0, 4]), damping=S(0.0), tol=S(1e-10), max_iter=Int(50))

# -- dqlab.identify ------------------------------------------------------------------------

M = "identify"
case(M, "fit_linear", identify.fit_linear, A=A(A_FIT), b=A(B_FIT),
     names=O(["a", "b", "c"], none_ok=True), reference=A([0.0, 0.0, 0.0], none_ok=True),
     rank_tol=S(1e-8), max_condition=S(1e6, inf_ok=True))
case(M, "desk_arm_regressor", identify.desk_arm_regressor, q_lab=A(Q_LAB))
case(M, "identify_desk_arm", identify.identify_desk_arm, q_lab=A(Q_LAB), positions=A(P_LAB),
     rank_tol=S(1e-8), max_condition=S(1e6, inf_ok=True))
case(M, "dh_parameter_names", identify.dh_parameter_names, robot=O(DESK))
case(M, "dh_parameters", identify.dh_parameters, robot=O(DESK))
case(M, "robot_from_dh_parameters", lambda **kw: identify.robot_from_dh_parameters(**kw).fk(
    np.zeros(3)), robot=O(DESK), parameters=A(identify.dh_parameters(DESK) + 0.001))
case(M, "identification_jacobian", identify.identification_jacobian, robot=O(DESK),
     q=A(Q_DESK[:2]), measure=O("pose"))
case(M, "identify_dh_parameters", identify.identify_dh_parameters, robot=O(DESK), q=A(Q_DESK),
     measured=A(DESK.fk(Q_DESK)[:, :3, 3] + 1e-4), measure=O("position"),
     fixed=O(["theta1"], none_ok=True), rotation_scale=S(0.1), rank_tol=S(1e-8),
     max_condition=S(1e8, inf_ok=True), tol=S(1e-12), max_iter=Int(20))
case(M, "identify_dh_parameters(pose)",
     lambda **kw: identify.identify_dh_parameters(DESK, Q_DESK, DESK.fk(Q_DESK), measure="pose",
                                                  **kw),
     rotation_scale=S(0.1), max_condition=S(1e12, inf_ok=True))
case(M, "Identification.value", FIT.value, name=O("b"))
case(M, "Identification.summary", FIT.summary, scale=S(1000.0), unit=T("mm"))

# -- dqlab.pick_place and its animation --------------------------------------------------

M = "pick_place"
case(M, "PickPlaceTask", pp.PickPlaceTask, positions=A(TASK.positions),
     suction=A(TASK.suction.astype(float)), wrist=A(TASK.wrist))
case(M, "task_from_lab", pp.task_from_lab, rows=A(LAB_ROWS))
case(M, "joint_targets", pp.joint_targets, robot=O(DESK), task=O(TASK), branch=O(0),
     wrist_limits=A([-np.pi, np.pi]), tol=S(1e-9))
case(M, "cup_poses", pp.cup_poses, robot=O(DESK), q=A(PLAN.targets))
case(M, "plan_pick_place", pp.plan_pick_place, robot=O(DESK), task=O(TASK),
     object_pose=A(PLAN.object[0], none_ok=True), branch=O(0),
     wrist_limits=A([-np.pi, np.pi]), v_max=S(1.0), a_max=S(4.0), dwell=S(0.3), dt=S(0.1),
     grasp_tol=S(0.002, inf_ok=True))


def _animate(**kw):
    viz = pytest.importorskip("dqlab.viz")
    kw.setdefault("scene", viz.Scene())
    viz.animate_pick_place(**kw)
    return np.zeros(1)


case(M, "viz.animate_pick_place", _animate, robot=O(DESK), plan=O(PLAN),
     size=A([0.06, 0.04, 0.004]), stride=Int(3))

# -- dqlab.reachability and dqlab.dask_arrays ------------------------------------------------

M = "reachability"
case(M, "pose_dexterity", pose_dexterity, robot=O(UR3), poses=A(UR3.fk(Q6)))
case(M, "super_fibonacci_quaternions", super_fibonacci_quaternions, k=Int(5))
case(M, "reachability_statistics", reachability_statistics, robot=O(UR3), positions=A(GRID),
     orientations=A(QUATS), block=Int(64))
RMAP = reachability_statistics(UR3, GRID, QUATS)
case(M, "ReachabilityMap", ReachabilityMap, positions=A(RMAP.positions),
     orientations=A(RMAP.orientations), reachable=A(RMAP.reachable),
     branches=A(RMAP.branches), median_manipulability=A(RMAP.median_manipulability))
case(M, "ReachabilityMap.save", lambda path: RMAP.save(path), path=P("map.npz"), writes="path",
     check=lambda _, kw: _reads_back(kw["path"], RMAP))
case(M, "check_ik_options", lambda **kw: check_ik_options(options={"tol": 1e-9}, **kw),
     robot=O(UR3), kind=O((4, 4)))
case(M, "ReachabilityMap.load", ReachabilityMap.load, path=F("map.npz"),
     setup=lambda folder: RMAP.save(folder / "map.npz"))


def _computed(*arrays):
    dask = pytest.importorskip("dask")
    return dask.compute(*arrays, scheduler="synchronous")


def _fk_dask(**kw):
    from dqlab.dask_arrays import fk_dask
    return _computed(fk_dask(**kw))


def _ik_ur_dask(**kw):
    from dqlab.dask_arrays import ik_ur_dask
    result = ik_ur_dask(**kw)
    return _computed(result.solutions, result.position_error)


def _dexterity_dask(**kw):
    from dqlab.dask_arrays import dexterity_dask
    return _computed(*dexterity_dask(**kw))


def _reachability_map(**kw):
    pytest.importorskip("dask")
    from dqlab.dask_arrays import reachability_map
    return reachability_map(**kw)


M = "dask_arrays"
case(M, "fk_dask", _fk_dask, robot=O(UR3), q=A(np.stack([Q6, -Q6])))
case(M, "ik_ur_dask", _ik_ur_dask, robot=O(UR3), poses=A(UR3.fk(np.stack([Q6, -Q6]))),
     tol=S(1e-9, inf_ok=True))
case(M, "dexterity_dask", _dexterity_dask, robot=O(UR3), poses=A(UR3.fk(np.stack([Q6, -Q6]))))
case(M, "reachability_map", _reachability_map, robot=O(UR3), positions=A(GRID),
     orientations=A(QUATS), chunk=Int(1, none_ok=True),
     scheduler=O("synchronous", none_ok=True),
     block=Int(64))

# -- dqlab.sim -----------------------------------------------------------------------------

M = "sim"


def _sim():
    sim = pytest.importorskip("dqlab.sim")
    pytest.importorskip("mujoco")
    if "sim" not in _SIM:
        _SIM["sim"] = sim.ArmSimulation(UR3)
    return _SIM["sim"]


_SIM = {}


def _mjcf(**kw):
    mujoco = pytest.importorskip("mujoco")
    from dqlab.sim import mjcf_from_robot
    xml = mjcf_from_robot(**kw)
    mujoco.MjModel.from_xml_string(xml)          # what it writes, MuJoCo loads
    return xml


def _urdf(**kw):
    from dqlab.sim import urdf_from_robot
    text = urdf_from_robot(**kw)
    ElementTree.fromstring(text)                 # what it writes, an XML reader parses
    return text


def _placements(**kw):
    from dqlab.sim import link_placements
    return link_placements(**kw)


def _default_masses(**kw):
    from dqlab.sim import default_masses
    return default_masses(**kw)


def _arm_simulation(**kw):
    _sim()
    from dqlab.sim import ArmSimulation
    return ArmSimulation(**kw).gravity_torque(Q6)


def _method(name):
    def call(**kw):
        sim = _sim()
        sim.reset(Q6)
        return getattr(sim, name)(**kw)
    return call


def _step(**kw):
    sim = _sim()
    sim.reset(Q6)
    sim.step(**kw)
    return sim.q


def _payload(payload):
    sim = _sim()
    try:
        sim.payload = payload
        return sim.gravity_torque(Q6)
    finally:
        sim.payload = 0.0


def _track(controller="computed torque", **kw):
    from dqlab.sim import ComputedTorque, JointPD, track
    sim = kw.pop("sim", None) or _sim()
    kw.setdefault("trajectory", TRAJ)
    if controller == "computed torque":
        controller = ComputedTorque(**{k: kw.pop(k) for k in ("kp", "kd") if k in kw})
    elif controller == "PD":
        controller = JointPD(kp=kw.pop("kp", 300.0), kd=kw.pop("kd", 20.0),
                             gravity_compensation=True)
    result = track(sim, controller=controller, **kw)
    return result.q, result.torque, result.flange_error


def _frames(fps):
    from dqlab.sim import ComputedTorque, track
    return track(_sim(), TRAJ, ComputedTorque()).frames(fps)


def _check_trajectory(**kw):
    from dqlab.sim import check_trajectory
    return check_trajectory(**kw)


def _sample_reference(**kw):
    from dqlab.sim.simulation import sample_reference
    return sample_reference(**kw)


case(M, "mjcf_from_robot", _mjcf, robot=O(UR3), masses=A([2.0, 3.4, 1.3, 0.8, 0.8, 0.35],
     none_ok=True), payload=S(0.5), radius=S(0.03, none_ok=True), damping=A([0.1] * 6),
     armature=S(0.01), timestep=S(0.002), integrator=O("RK4"), gravity=S(9.81),
     base_mass=S(2.0, none_ok=True), name=Name("arm", none_ok=True))
case(M, "urdf_from_robot", _urdf, robot=O(UR3), masses=A([2.0, 3.4, 1.3, 0.8, 0.8, 0.35],
     none_ok=True), name=Name("arm", none_ok=True))
case(M, "link_placements", _placements, robot=O(UR3))
case(M, "default_masses", _default_masses, robot=O(DESK))
case(M, "ArmSimulation", _arm_simulation, robot=O(UR3))
case(M, "ArmSimulation.reset", _method("reset"), q=A(Q6), qd=A(np.zeros(6), none_ok=True),
     time=S(1.0))
case(M, "ArmSimulation.check_target", _method("check_target"), q=A(Q6))
case(M, "ArmSimulation.flange_positions", _method("flange_positions"), q=A(np.stack([Q6, Q6])))
case(M, "ArmSimulation.step", _step, torque=A(np.ones(6)), steps=Int(3))
case(M, "ArmSimulation.inverse_dynamics", _method("inverse_dynamics"), q=A(Q6),
     qd=A(np.ones(6)), qdd=A(np.ones(6)))
case(M, "ArmSimulation.gravity_torque", _method("gravity_torque"), q=A(Q6))
case(M, "ArmSimulation.mass_matrix", _method("mass_matrix"), q=A(Q6))
case(M, "ArmSimulation.payload", _payload, payload=S(1.5))
case(M, "track", _track, sim=O(None, none_ok=True), trajectory=O(TRAJ), payload=A(
     np.linspace(0.0, 1.0, len(TRAJ)), none_ok=True))
case(M, "track(controller)", lambda controller: _track(controller=controller),
     controller=O("computed torque"))
case(M, "ComputedTorque", _track, kp=A([400.0] * 6), kd=S(40.0))
case(M, "JointPD", lambda **kw: _track(controller="PD", **kw), kp=S(300.0), kd=A([20.0] * 6))
case(M, "TrackingResult.frames", _frames, fps=S(25.0))


def _torque(controller):
    def call(**kw):
        from dqlab.sim import ComputedTorque, JointPD
        law = ComputedTorque() if controller == "computed torque" else JointPD(
            kp=300.0, kd=20.0, gravity_compensation=True)
        sim = kw.pop("sim", None) or _sim()
        if sim is _sim():
            sim.reset(Q6)
        return law.torque(sim, **kw)
    return call


for controller in ("computed torque", "PD"):
    case(M, f"{controller}.torque", _torque(controller), sim=O(None, none_ok=True),
         q_d=A(Q6 + 0.01), qd_d=A(np.full(6, 0.1)), qdd_d=A(np.full(6, -0.2)))
case(M, "check_trajectory", _check_trajectory, trajectory=O(TRAJ), robot=O(UR3))
case(M, "sample_reference", _sample_reference, t=A(TRAJ.t), q=A(TRAJ.q), qd=A(TRAJ.qd),
     qdd=A(TRAJ.qdd), times=Any([0.01, 0.1, 0.15]), velocity_lag=S(0.001))


# -- the sweep -----------------------------------------------------------------------------

def _reads_back(path, written):
    """A check of a writer: the file it wrote reads back as what it was given."""
    back = type(written).load_csv(path) if hasattr(written, "save_csv") else type(
        written).load(path if str(path).endswith(".npz") else f"{path}.npz")
    same = all(np.array_equal(getattr(back, k), getattr(written, k))
               for k in ("t", "q", "positions", "reachable") if hasattr(written, k))
    return True if same else f"{path} reads back as something else"



@pytest.mark.sweep
@pytest.mark.parametrize("title", list(CASES))
def test_bad_arguments_are_refused_by_name_or_give_a_correct_result(title, request, tmp_path):
    sweep_test(request, CASES[title], tmp_path, "applications")
