"""Every public callable of ``dqlab.ur`` and the MuJoCo back end, every argument, every kind of
bad value (``tests/_sweep.py``: NaN, inf, None, text, complex numbers, the wrong shape, a
ragged list, an empty batch, huge, tiny and far magnitudes; a single number also a boolean, a
number as text and a numpy number; an integer also a fraction and integers beyond 64 bits; a
host name text that cannot be one).

Each call must either raise ``ValueError`` or ``TypeError`` whose message names the argument
(by its name, or by how the command calls it: a ``movej``'s ``q`` is its "target"), or return
a correct result: finite (a text, a state, a file written) for huge and tiny magnitudes, of
size 0 for an empty batch, anything for ``inf`` given as a tolerance (``inf`` switches a
check off). Anything else fails. The session's summary counts the outcomes.
"""

from types import SimpleNamespace

import numpy as np
import pytest
from _sweep import Arg, F, Name, P, Registry, folder, sweep_test

import dqlab
from dqlab import ur
from dqlab.models import ur3
from dqlab.ur import calibration, rtde, script
from dqlab.ur.calibration import CalibrationConf

UR3 = ur3()
Q0 = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])           # a regular configuration
Q1 = Q0 + [0.1, -0.05, 0.05, 0.0, 0.1, -0.1]
POSE = ur.pose_from_transform(UR3.fk(Q0))
GOAL = POSE + [0.02, -0.01, -0.02, 0.0, 0.0, 0.0]
R3 = np.array([0.1, -0.2, 0.3])
QUAT = ur.quaternion_from_rotation_vector(R3)
ROT = ur.matrix_from_rotation_vector(R3)
T = UR3.fk(Q0)
DQ = UR3.fk_dq(Q0)
T_TRAJ = np.arange(51) * 0.01
Q_TRAJ = Q0 + np.outer(0.5 * (1 - np.cos(np.pi * T_TRAJ / T_TRAJ[-1])), [0.1, 0.05, 0, 0, 0, 0])


def traj(t=T_TRAJ, q=Q_TRAJ):
    return SimpleNamespace(t=t, q=q)


class Client:
    """A connected URClient on a kinematic arm at Q0 (fresh for each call)."""

    def __getattr__(self, name):
        client = ur.URClient(ur.KinematicBackend(q0=Q0, clock=ur.StepClock(0.01)),
                             poll_interval=0)
        client.connect()
        return getattr(client, name)


def arm():
    a = ur.KinematicBackend(q0=Q0, clock=ur.StepClock(0.01))
    a.connect()
    return a


_MUJOCO = []


def mujoco():
    """One MuJoCo back end for the sweep, restarted at Q0 for each call."""
    if not _MUJOCO:
        sim = pytest.importorskip("dqlab.sim", reason="MuJoCo (extra 'sim') is not installed")
        _MUJOCO.append(sim.MujocoBackend(q_home=Q0))
    _MUJOCO[0].connect(timeout=1.0)
    return _MUJOCO[0]


def good_file(tmp):
    path = tmp / "good.csv"
    if not path.exists():
        ur.write_poses(path, [POSE, GOAL])
    return path


TARGET = ("target",)
TOL = dict(inf_ok=True)
DEFAULT_NONE = dict(none_ok=True)            # None is the argument's default: "not given"
#: (name, call(value, tmp_path), good value, names the message may use, options)
CASES_ = [
    # poses
    ("check_pose.p", lambda v, tmp: ur.check_pose(v), POSE, ("p", "pose"), {}),
    ("dual_quaternion_from_pose.p", lambda v, tmp: ur.dual_quaternion_from_pose(v), POSE,
     ("p",), {}),
    ("transform_from_pose.p", lambda v, tmp: ur.transform_from_pose(v), POSE, ("p", "r"), {}),
    ("quaternion_from_rotation_vector.r", lambda v, tmp: ur.quaternion_from_rotation_vector(v),
     R3, ("r",), {}),
    ("matrix_from_rotation_vector.r", lambda v, tmp: ur.matrix_from_rotation_vector(v), R3,
     ("r",), {}),
    ("rpy_from_rotation_vector.r", lambda v, tmp: ur.rpy_from_rotation_vector(v), R3, ("r",),
     {}),
    ("rpy_from_rotation_vector.singular_tol",
     lambda v, tmp: ur.rpy_from_rotation_vector(R3, singular_tol=v), 1e-12, ("singular_tol",),
     TOL),
    ("rotation_vector_from_rpy.rpy", lambda v, tmp: ur.rotation_vector_from_rpy(v), R3,
     ("rpy",), {}),
    ("rotation_vector_from_rpy.half_turn_tol",
     lambda v, tmp: ur.rotation_vector_from_rpy(R3, half_turn_tol=v), 1e-12,
     ("half_turn_tol",), TOL),
    ("rotation_vector_from_quaternion.q", lambda v, tmp: ur.rotation_vector_from_quaternion(v),
     QUAT, ("q",), {}),
    ("rotation_vector_from_quaternion.tol",
     lambda v, tmp: ur.rotation_vector_from_quaternion(QUAT, tol=v), 1e-9,
     ("tol", "tolerance"), TOL),
    ("rotation_vector_from_quaternion.half_turn_tol",
     lambda v, tmp: ur.rotation_vector_from_quaternion(QUAT, half_turn_tol=v), 1e-12,
     ("half_turn_tol",), TOL),
    ("rotation_vector_from_matrix.R", lambda v, tmp: ur.rotation_vector_from_matrix(v), ROT,
     ("R",), {}),
    ("rotation_vector_from_matrix.tol",
     lambda v, tmp: ur.rotation_vector_from_matrix(ROT, tol=v), 1e-9, ("tol", "tolerance"), TOL),
    ("pose_from_transform.T", lambda v, tmp: ur.pose_from_transform(v), T, ("T",), {}),
    ("pose_from_transform.tol", lambda v, tmp: ur.pose_from_transform(T, tol=v), 1e-9,
     ("tol", "tolerance"), TOL),
    ("pose_from_dual_quaternion.Q", lambda v, tmp: ur.pose_from_dual_quaternion(v), DQ,
     ("Q",), {}),
    ("pose_from_dual_quaternion.tol", lambda v, tmp: ur.pose_from_dual_quaternion(DQ, tol=v),
     1e-9, ("tol", "tolerance", "Q"), TOL),           # too tight a tol: Q is not unit within
    # pose files
    ("write_poses.values", lambda v, tmp: ur.write_poses(tmp / "w.csv", v),
     np.stack([POSE, GOAL]), ("values", "pose"), {}),
    ("write_poses.max_reach", lambda v, tmp: ur.write_poses(tmp / "w.csv", [POSE], max_reach=v),
     2.0, ("max_reach",), TOL),
    ("write_poses.unit_tol", lambda v, tmp: ur.write_poses(tmp / "w.csv", [DQ], unit_tol=v,
                                                           kind="dual_quaternion"),
     1e-9, ("unit_tol",), TOL),
    ("append_pose.value", lambda v, tmp: ur.append_pose(tmp / "a.csv", v), POSE,
     ("value", "pose"), {}),
    ("append_pose.max_reach", lambda v, tmp: ur.append_pose(tmp / "a.csv", POSE, max_reach=v),
     2.0, ("max_reach",), TOL),
    ("read_poses.max_reach", lambda v, tmp: ur.read_poses(good_file(tmp), max_reach=v), 2.0,
     ("max_reach",), TOL),
    ("read_poses.unit_tol", lambda v, tmp: ur.read_poses(good_file(tmp), unit_tol=v), 1e-9,
     ("unit_tol",), TOL),
    # URScript
    ("movej.q", lambda v, tmp: ur.movej(v), Q1, TARGET, {}),
    ("movej.a", lambda v, tmp: ur.movej(Q1, a=v), 1.4, ("a",), {}),
    ("movej.v", lambda v, tmp: ur.movej(Q1, v=v), 1.05, ("v",), {}),
    ("movej.t", lambda v, tmp: ur.movej(Q1, t=v, q_from=Q0), 2.0, ("t",), {}),
    ("movej.r", lambda v, tmp: ur.movej(Q1, r=v), 0.01, ("r",), {}),
    ("movej.q_from", lambda v, tmp: ur.movej(Q1, q_from=v), Q0, ("q_from",), DEFAULT_NONE),
    ("movel.pose", lambda v, tmp: ur.movel(v), GOAL, TARGET, {}),
    ("movel.a", lambda v, tmp: ur.movel(GOAL, a=v, q_from=Q0), 1.2, ("a",), {}),
    ("movel.v", lambda v, tmp: ur.movel(GOAL, v=v), 0.25, ("v",), {}),
    ("movel.t", lambda v, tmp: ur.movel(GOAL, t=v, q_from=Q0), 1.0, ("t",), {}),
    ("movel.r", lambda v, tmp: ur.movel(GOAL, r=v), 0.01, ("r",), {}),
    ("movel.q_from", lambda v, tmp: ur.movel(GOAL, q_from=v), Q0, ("q_from",) + TARGET,
     DEFAULT_NONE),
    ("servoj.q", lambda v, tmp: ur.servoj(v), Q1, TARGET, {}),
    ("servoj.t", lambda v, tmp: ur.servoj(Q1, t=v, q_from=Q0), 0.5, ("t",), {}),
    ("servoj.lookahead_time", lambda v, tmp: ur.servoj(Q1, lookahead_time=v), 0.1,
     ("lookahead_time",), {}),
    ("servoj.gain", lambda v, tmp: ur.servoj(Q1, gain=v), 300.0, ("gain",), {}),
    ("servoj.q_from", lambda v, tmp: ur.servoj(Q1, t=0.5, q_from=v), Q0, ("q_from",),
     DEFAULT_NONE),
    ("stopj.a", lambda v, tmp: ur.stopj(v), 2.0, ("a",), {}),
    ("program_from_trajectory.t", lambda v, tmp: ur.program_from_trajectory(traj(t=v)), T_TRAJ,
     ("t", "times", "time"), {}),
    ("program_from_trajectory.q", lambda v, tmp: ur.program_from_trajectory(traj(q=v)), Q_TRAJ,
     ("q",) + TARGET, {}),
    ("program_from_trajectory.a",
     lambda v, tmp: ur.program_from_trajectory(traj(), a=v, q_from=Q0), 1.4, ("a",), {}),
    ("program_from_trajectory.v", lambda v, tmp: ur.program_from_trajectory(traj(), v=v), 1.05,
     ("v",), {}),
    ("program_from_trajectory.lookahead_time",
     lambda v, tmp: ur.program_from_trajectory(traj(), lookahead_time=v), 0.1,
     ("lookahead_time",), {}),
    ("program_from_trajectory.gain", lambda v, tmp: ur.program_from_trajectory(traj(), gain=v),
     300.0, ("gain",), {}),
    ("program_from_trajectory.q_from",
     lambda v, tmp: ur.program_from_trajectory(traj(), q_from=v), Q0, ("q_from",),
     DEFAULT_NONE),
    ("check_joint_targets.times",
     lambda v, tmp: script.check_joint_targets(Q_TRAJ, times=v, command="x"), T_TRAJ,
     ("times", "t", "time"), DEFAULT_NONE),
    *[(f"SafetyLimits.{key}", lambda v, tmp, key=key: ur.SafetyLimits(**{key: v}), value,
       (key,), {})
      for key, value in [("joint_limits", script.UR3_JOINT_LIMITS[:5].tolist() + [[-7, 7]]),
                         ("max_joint_speed", script.UR3_MAX_JOINT_SPEED),
                         ("max_joint_acceleration", 10.0), ("max_joint_step", np.pi),
                         ("max_tcp_speed", 1.0), ("max_tcp_acceleration", 5.0)]],
    ("SafetyLimits.max_joint_torque",
     lambda v, tmp: ur.SafetyLimits(robot=UR3, max_joint_torque=v), script.UR3_MAX_JOINT_TORQUE,
     ("max_joint_torque",), DEFAULT_NONE),
    ("SafetyLimits.payload", lambda v, tmp: ur.SafetyLimits.for_robot(UR3, payload=v), 2.0,
     ("payload",), {}),
    ("SafetyLimits.payload_cog",
     lambda v, tmp: ur.SafetyLimits.for_robot(UR3, payload=2.0, payload_cog=v),
     np.array([0.0, 0.0, 0.1]), ("payload_cog",), {}),
    ("Motion.samples.period",
     lambda v, tmp: ur.motion.plan_movej(Q0, Q1).samples(v)[1], 0.008, ("period",), {}),
    *[(f"SafetyLimits.joint_torques.{name}",
       lambda v, tmp, i=i: ur.SafetyLimits.for_robot(UR3, payload=2.0).joint_torques(
           *[v if k == i else Q_TRAJ * 0.5 for k in range(3)]), Q_TRAJ, (name,), {})
      for i, name in enumerate(("q", "qd", "qdd"))],
    # the client, on the kinematic arm
    ("URClient.tol", lambda v, tmp: ur.URClient(arm(), tol=v), 1e-4, ("tol",), TOL),
    ("URClient.poll_interval", lambda v, tmp: ur.URClient(arm(), poll_interval=v), 0.002,
     ("poll_interval",), {}),
    ("URClient.connect_timeout", lambda v, tmp: ur.URClient(arm(), connect_timeout=v), 5.0,
     ("connect_timeout",), {}),
    ("URClient.movej.q", lambda v, tmp: Client().movej(v, wait=False), Q1, TARGET, {}),
    ("URClient.movej.a", lambda v, tmp: Client().movej(Q1, a=v, wait=False), 1.4, ("a",), {}),
    ("URClient.movej.v", lambda v, tmp: Client().movej(Q1, v=v, wait=False), 1.05, ("v",), {}),
    ("URClient.movej.t", lambda v, tmp: Client().movej(Q1, t=v, wait=False), 1.0, ("t",), {}),
    ("URClient.movej.r", lambda v, tmp: Client().movej(Q1, r=v, wait=False), 0.0, ("r",), {}),
    ("URClient.movej.timeout", lambda v, tmp: Client().movej(Q1, timeout=v), 5.0,
     ("timeout",), dict(inf_ok=True, none_ok=True)),
    ("URClient.movel.pose", lambda v, tmp: Client().movel(v, wait=False), GOAL, TARGET, {}),
    ("URClient.movel.a", lambda v, tmp: Client().movel(GOAL, a=v, wait=False), 1.2, ("a",),
     {}),
    ("URClient.movel.v", lambda v, tmp: Client().movel(GOAL, v=v, wait=False), 0.25, ("v",),
     {}),
    ("URClient.movel.t", lambda v, tmp: Client().movel(GOAL, t=v, wait=False), 1.0, ("t",), {}),
    ("URClient.servoj_stream.t", lambda v, tmp: Client().servoj_stream(traj(t=v), timeout=2),
     T_TRAJ, ("t", "times", "time"), {}),
    ("URClient.servoj_stream.q", lambda v, tmp: Client().servoj_stream(traj(q=v), timeout=2),
     Q_TRAJ, ("q",) + TARGET, {}),
    ("URClient.servoj_stream.start_tol",
     lambda v, tmp: Client().servoj_stream(traj(), start_tol=v), 1e-3, ("start_tol",), TOL),
    ("URClient.servoj_stream.gain", lambda v, tmp: Client().servoj_stream(traj(), gain=v),
     300.0, ("gain",), {}),
    ("URClient.stop.a", lambda v, tmp: Client().stop(v), 2.0, ("a",), {}),
    ("URClient.closest_joints.pose", lambda v, tmp: Client().closest_joints(v), GOAL,
     ("pose", "T"), {}),
    # the kinematic arm and its clock
    ("KinematicBackend.q0", lambda v, tmp: ur.KinematicBackend(q0=v), Q0, ("q0",),
     DEFAULT_NONE),
    ("KinematicBackend.speedup", lambda v, tmp: ur.KinematicBackend(speedup=v), 1.0,
     ("speedup",), {}),
    ("StepClock.dt", lambda v, tmp: ur.StepClock(v), 0.01, ("dt",), {}),
    ("KinematicBackend.movej.q", lambda v, tmp: arm().movej(v), Q1, TARGET, {}),
    ("KinematicBackend.movej.t", lambda v, tmp: arm().movej(Q1, t=v), 1.0, ("t",), {}),
    ("KinematicBackend.movel.pose", lambda v, tmp: arm().movel(v), GOAL, TARGET, {}),
    ("KinematicBackend.servoj.q", lambda v, tmp: arm().servoj(v, t=0.5), Q1, TARGET, {}),
    ("KinematicBackend.servoj.t", lambda v, tmp: arm().servoj(Q1, t=v), 0.5, ("t",), {}),
    ("KinematicBackend.stop.a", lambda v, tmp: arm().stop(v), 2.0, ("a",), {}),
    # network back ends and the stand-in (constructed, not connected)
    ("SecondaryInterfaceBackend.host",
     lambda v, tmp: ur.SecondaryInterfaceBackend(v), "127.0.0.1", ("host",), {}),
    ("SecondaryInterfaceBackend.port",
     lambda v, tmp: ur.SecondaryInterfaceBackend("127.0.0.1", v), 30002, ("port",), {}),
    ("SecondaryInterfaceBackend.frequency",
     lambda v, tmp: ur.SecondaryInterfaceBackend("127.0.0.1", frequency=v), 125.0,
     ("frequency",), {}),
    ("RTDEReader.port", lambda v, tmp: rtde.RTDEReader("127.0.0.1", v), 30004, ("port",), {}),
    ("ControllerStandIn.q0", lambda v, tmp: ur.ControllerStandIn(q0=v), Q0, ("q0",),
     DEFAULT_NONE),
    ("ControllerStandIn.speedup", lambda v, tmp: ur.ControllerStandIn(speedup=v), 5.0,
     ("speedup",), {}),
    ("ControllerStandIn.rtde_port", lambda v, tmp: ur.ControllerStandIn(rtde_port=v), 0,
     ("rtde_port",), {}),
    ("ControllerStandIn.controller_version",
     lambda v, tmp: ur.ControllerStandIn(controller_version=v), (5, 11, 0, 0),
     ("controller_version",), {}),
    ("ControllerStandIn.start_timeout", lambda v, tmp: ur.ControllerStandIn(start_timeout=v),
     30.0, ("start_timeout",), {}),
    ("ControllerStandIn.primary_port", lambda v, tmp: ur.ControllerStandIn(primary_port=v), 0,
     ("primary_port",), {}),
    ("kinematics_info_from_robot.checksum",
     lambda v, tmp: calibration.kinematics_info_from_robot(UR3, checksum=v), (7,) * 6,
     ("checksum",), {}),
    ("kinematics_info_from_robot.calibration_status",
     lambda v, tmp: calibration.kinematics_info_from_robot(UR3, calibration_status=v), 2,
     ("calibration_status",), {}),
    ("ControllerStandIn.calibration",
     lambda v, tmp: ur.ControllerStandIn(calibration=CalibrationConf(v, v, v, v)), (0.0,) * 6,
     ("delta_theta", "calibration"), {}),
    # the MuJoCo back end
    ("MujocoBackend.movej.q", lambda v, tmp: mujoco().movej(v), Q1, ("q",), {}),
    ("MujocoBackend.movej.a", lambda v, tmp: mujoco().movej(Q1, a=v), 1.4, ("a",), {}),
    ("MujocoBackend.movej.v", lambda v, tmp: mujoco().movej(Q1, v=v), 1.05, ("v",), {}),
    ("MujocoBackend.movej.t", lambda v, tmp: mujoco().movej(Q1, t=v), 1.0, ("t", "q"), {}),
    ("MujocoBackend.movej.r", lambda v, tmp: mujoco().movej(Q1, r=v), 0.0, ("r",), {}),
    ("MujocoBackend.movel.pose", lambda v, tmp: mujoco().movel(v), GOAL, ("pose",), {}),
    ("MujocoBackend.movel.a", lambda v, tmp: mujoco().movel(GOAL, a=v), 1.2, ("a", "pose"),
     {}),
    ("MujocoBackend.movel.v", lambda v, tmp: mujoco().movel(GOAL, v=v), 0.25, ("v", "pose"),
     {}),
    ("MujocoBackend.servoj.q", lambda v, tmp: mujoco().servoj(v, t=0.5), Q1, ("q",), {}),
    ("MujocoBackend.servoj.t", lambda v, tmp: mujoco().servoj(Q1, t=v), 0.5, ("t", "q"), {}),
    ("MujocoBackend.servoj.gain", lambda v, tmp: mujoco().servoj(Q1, t=0.5, gain=v), 300.0,
     ("gain",), {}),
    ("MujocoBackend.stop.a", lambda v, tmp: mujoco().stop(v), 2.0, ("a", "q"), {}),
    ("MujocoBackend.advance.duration", lambda v, tmp: mujoco().advance(v), 0.01,
     ("duration",), {}),
    ("MujocoBackend.q_home",
     lambda v, tmp: __import__("dqlab.sim").sim.MujocoBackend(q_home=v), Q0, ("q_home",), {}),
    ("MujocoBackend.period",
     lambda v, tmp: __import__("dqlab.sim").sim.MujocoBackend(period=v), 0.008, ("period",),
     {}),
]

def _kind(good):
    """The sweep's kind of an argument: a host is text, a port or a count an integer, one
    number a scalar, anything else an array."""
    if isinstance(good, str):
        return "text"
    if isinstance(good, (int, np.integer)) and not isinstance(good, bool):
        return "int"
    return "scalar" if np.ndim(good) == 0 else "array"


CASES = Registry()
for _name, _call, _good, _names, _options in CASES_:
    _label = _name.rsplit(".", 1)[1]
    _arg = Arg(_good, _kind(_good), _options.get("none_ok", False),
               _options.get("inf_ok", False), tuple(_names))
    CASES.add("ur" if not _name.startswith("Mujoco") else "sim.backend", _name,
              lambda _call=_call, **kw: _call(next(iter(kw.values())), folder()),
              group=_name.rsplit(".", 1)[0], **{_label: _arg})


def _reads_back(written, values):
    back = ur.read_poses(written)
    return True if np.array_equal(back.values, np.atleast_2d(values)) else "reads back wrong"


# the pose files themselves: a file to read, a file to write over, the header's texts
CASES.add("ur", "read_poses.path", ur.read_poses, path=F("good.csv"), group="read_poses")
CASES.add("ur", "write_poses.path", lambda **kw: ur.write_poses(values=[POSE, GOAL], **kw)
          or kw["path"], path=P("w.csv"), writes="path", group="write_poses",
          check=lambda path, kw: _reads_back(path, [POSE, GOAL]))
CASES.add("ur", "write_poses.header", lambda **kw: ur.write_poses("h.csv", [POSE], **kw)
          or "h.csv", robot=Name("UR3"), frame=Name("base"), tcp=Name("flange"),
          group="write_poses", check=lambda path, kw: _reads_back(path, [POSE]))
CASES.add("ur", "append_pose.path", lambda **kw: ur.append_pose(value=GOAL, **kw),
          path=P("a.csv"), writes="path", group="append_pose")
for _case in CASES.values():
    _case.setup = good_file


@pytest.mark.sweep
@pytest.mark.parametrize("group", list(CASES.groups))
def test_bad_arguments_are_refused_by_name_or_give_a_correct_result(group, request, tmp_path):
    sweep_test(request, CASES.groups[group], tmp_path, "ur")


def test_the_sweep_covers_every_public_name_of_dqlab_ur():
    swept = {c[0].split(".")[0] for c in CASES_}
    data = {"HOME", "ROBOT_MODE_RUNNING", "Backend", "URState", "PoseFile", "PoseFileError",
            "UnsafeTargetError", "ControllerError"}
    untested = {"RTDEBackend"}                       # needs ur_rtde (tests/test_ur_standin.py)
    assert set(ur.__all__) - data - untested <= swept, set(ur.__all__) - data - swept
    assert dqlab.ur.RTDEBackend
