"""A calibrated arm behind the controller stand-in: its kinematics info, its TCP, IK on it."""

import zlib
from dataclasses import replace
from struct import pack

import numpy as np
import pytest

from dqlab import ik
from dqlab.models import ur3, ur5e
from dqlab.ur import ControllerStandIn, URClient, pose_from_transform, transform_from_pose
from dqlab.ur.calibration import (
    UNCALIBRATED,
    CalibrationConf,
    CalibrationError,
    read_calibration_conf,
    read_kinematics_info,
    robot_from_calibration_conf,
    robot_from_corrections,
    robot_from_kinematics_info,
)
from dqlab.ur.motion import controller_pose

psutil = pytest.importorskip("psutil", reason="psutil (test extra) checks for leftovers")

RNG = np.random.default_rng(3107)
#: corrections of a few tenths of a millimetre and of a milliradian, as a factory's
FACTORY = CalibrationConf(*(tuple(RNG.uniform(-5e-4, 5e-4, 6).tolist()) for _ in range(4)),
                          joint_checksum=(11, 22, 33, 44, 55, 66), calibration_status=2)
Q = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])


def _conf_text(conf):
    lines = ["[mounting]"]
    for field in ("delta_theta", "delta_a", "delta_d", "delta_alpha"):
        lines.append(f"{field} = [ {', '.join(repr(v) for v in getattr(conf, field))}]")
    lines.append(f"joint_checksum = [ {', '.join(str(c) for c in conf.joint_checksum)}]")
    lines.append(f"calibration_status = {conf.calibration_status}")
    return "\n".join(lines) + "\n"


def test_corrections_give_the_arm_of_the_same_calibration_conf(tmp_path):
    path = tmp_path / "calibration.conf"
    path.write_text(_conf_text(FACTORY))
    assert read_calibration_conf(path) == FACTORY
    from_file = robot_from_calibration_conf(path, "UR3")
    from_corrections = robot_from_corrections(FACTORY, "UR3")
    q = RNG.uniform(-np.pi, np.pi, (20, 6))
    assert np.array_equal(from_file.fk(q), from_corrections.fk(q))
    nominal = ur3()
    for calibrated, published, k in zip(from_corrections.links, nominal.links, range(6),
                                        strict=True):
        assert calibrated.a == published.a + FACTORY.delta_a[k]
        assert calibrated.d == published.d + FACTORY.delta_d[k]
        assert calibrated.alpha == published.alpha + FACTORY.delta_alpha[k]
        assert calibrated.theta_offset == published.theta_offset + FACTORY.delta_theta[k]
    gap = np.linalg.norm(from_corrections.fk(q)[:, :3, 3] - nominal.fk(q)[:, :3, 3], axis=-1)
    assert 1e-4 < gap.max() < 5e-3                      # millimetres, as a calibration


@pytest.mark.parametrize("field, value, match", [
    ("delta_a", (0.0,) * 5, "delta_a: must be 6 finite numbers"),
    ("delta_d", (0.0, 0.0, np.nan, 0.0, 0.0, 0.0), "delta_d: must be 6 finite numbers"),
    ("delta_alpha", None, "delta_alpha: not a sequence of real numbers"),
    ("delta_theta", ("x",) * 6, "delta_theta: not a sequence of real numbers"),
    ("delta_a", (0.0, 0.1, 0.0, 0.0, 0.0, 0.0),
     "delta_theta, delta_a, delta_d, delta_alpha: the calibrated arm is"),
])
def test_bad_corrections_are_refused_naming_the_field(field, value, match):
    with pytest.raises(CalibrationError, match=match):
        robot_from_corrections(replace(FACTORY, **{field: value}), "UR3")
    with pytest.raises(TypeError, match="corrections must be a CalibrationConf"):
        robot_from_corrections(FACTORY.delta_a, "UR3")


def test_a_bad_calibration_is_refused_before_the_stand_in_starts():
    with pytest.raises(TypeError, match="calibration must be"):
        ControllerStandIn(calibration={"delta_a": (0.0,) * 6})
    with pytest.raises(CalibrationError, match="calibration: delta_d"):
        ControllerStandIn(calibration=replace(FACTORY, delta_d=(np.inf,) * 6))
    with pytest.raises(CalibrationError, match="not a UR5e|not a ur5e|the calibrated arm is"):
        ControllerStandIn("ur5e", calibration=replace(FACTORY, delta_a=(0, 0.2, 0, 0, 0, 0)))
    for bad, name in [(dict(calibration_status=2.7), "calibration.calibration_status"),
                      (dict(calibration_status=2 ** 32), "calibration.calibration_status"),
                      (dict(joint_checksum=(2 ** 40,) * 6), r"calibration.joint_checksum\[0\]"),
                      (dict(joint_checksum=(1,) * 5), "calibration.joint_checksum")]:
        with pytest.raises(ValueError, match=f"^{name} must be"):          # no process
            ControllerStandIn("ur5e", calibration=replace(FACTORY, **bad))
    assert psutil.Process().children(recursive=True) == []


def test_calibrated_stand_in_serves_its_calibration_and_moves_its_calibrated_arm():
    """Read the calibration from the controller, solve IK on it, movej: the controller's TCP
    is the target; the data sheet's solution misses it by the calibration's millimetres."""
    calibrated = robot_from_corrections(FACTORY, "UR3")
    X_target = calibrated.fk(Q)
    with ControllerStandIn(speedup=25, calibration=FACTORY) as standin:
        info = read_kinematics_info(standin.host, standin.secondary_port, timeout=10.0)
        arm = robot_from_kinematics_info(info, model="UR3")
        with URClient(standin.backend(robot=arm), poll_interval=0.001) as client:
            q_now = client.actual_q()
            q_calibrated = ik.closest_solution(ik.ur(arm, X_target), q_now)
            client.movej(q_calibrated)
            tcp_calibrated = client.actual_tcp_pose()
            q_data_sheet = ik.closest_solution(ik.ur(ur3(), X_target), q_now)
            client.movej(q_data_sheet)
            tcp_data_sheet = client.actual_tcp_pose()
        pid = standin.pid
    assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    assert info.checksum == FACTORY.joint_checksum and info.calibration_status == 2
    for field, key in (("theta", "delta_theta"), ("a", "delta_a"), ("d", "delta_d"),
                       ("alpha", "delta_alpha")):
        assert getattr(info, field) == tuple(getattr(lk, "theta_offset" if field == "theta"
                                                     else field) for lk in calibrated.links)
        assert getattr(FACTORY, key)
    assert np.array_equal(arm.fk(Q), calibrated.fk(Q))
    assert np.abs(q_calibrated - Q).max() < 1e-9              # the configuration it came from
    X_reached = transform_from_pose(tcp_calibrated)
    assert np.abs(X_reached - X_target).max() < 1e-9
    assert np.allclose(tcp_calibrated, controller_pose(calibrated, Q), atol=1e-9)
    miss = np.linalg.norm(transform_from_pose(tcp_data_sheet)[:3, 3] - X_target[:3, 3])
    assert 2e-4 < miss < 5e-3
    assert np.allclose(pose_from_transform(X_target), tcp_calibrated, atol=1e-9)


def test_without_checksums_the_stand_in_sends_a_crc_of_each_joints_corrections():
    conf = replace(FACTORY, joint_checksum=None, calibration_status=None)
    with ControllerStandIn("ur5e", calibration=conf) as standin:
        info = read_kinematics_info(standin.host, standin.secondary_port, timeout=10.0)
    expected = tuple(zlib.crc32(pack(">4d", conf.delta_theta[i], conf.delta_a[i],
                                     conf.delta_d[i], conf.delta_alpha[i])) for i in range(6))
    assert info.checksum == expected and UNCALIBRATED not in info.checksum
    assert info.calibration_status == 2
    q = RNG.uniform(-np.pi, np.pi, (10, 6))
    assert np.array_equal(robot_from_kinematics_info(info, model="UR5e").fk(q),
                          robot_from_corrections(conf, "UR5e").fk(q))
    assert not np.allclose(robot_from_kinematics_info(info).fk(q), ur5e().fk(q), atol=1e-4)
