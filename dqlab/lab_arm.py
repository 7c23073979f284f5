"""Deprecated: the former name of :mod:`dqlab.desk_arm_firmware` (the desktop arm's firmware:
its model, limits and G-code). Importing it warns with a :class:`DeprecationWarning`; its
names are those of :mod:`dqlab.desk_arm_firmware`, with ``uarm_swift_pro`` for
:func:`~dqlab.desk_arm_firmware.model` and ``UARM_SWIFT_PRO`` for
:data:`~dqlab.desk_arm_firmware.LENGTHS`."""

from ._deprecated import warn_renamed
from .desk_arm_firmware import (
    GCODE_REALTIME,
    MAX_FEED,
    MOTOR_LIMITS_DEG,
    gcode_from_plan,
    lab_angles_from_motor,
    motor_angles,
    motor_angles_from_lab,
    write_gcode,
)
from .desk_arm_firmware import LENGTHS as UARM_SWIFT_PRO
from .desk_arm_firmware import model as uarm_swift_pro

__all__ = ["UARM_SWIFT_PRO", "MOTOR_LIMITS_DEG", "MAX_FEED", "GCODE_REALTIME", "uarm_swift_pro",
           "motor_angles_from_lab", "lab_angles_from_motor", "motor_angles", "gcode_from_plan",
           "write_gcode"]

warn_renamed("dqlab.lab_arm", "dqlab.desk_arm_firmware (uarm_swift_pro is now model, "
             "UARM_SWIFT_PRO is now LENGTHS)")
