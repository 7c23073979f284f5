"""An independent decoder of UR primary/secondary-interface messages, for the tests only.

Written from UR's Client Library (UniversalRobots/Universal_Robots_Client_Library,
``include/ur_client_library/comm/bin_parser.h``, ``primary/primary_parser.h``,
``src/primary/robot_state/robot_mode_data.cpp``, ``kinematics_info.cpp``,
``robot_message/version_message.cpp``) and, for the joint data and cartesian info that the
library leaves undecoded, from UR's client-interface table as python-urx reads it
(``dddffffB`` per joint; six doubles of pose, six of TCP offset). It shares no code with
``dqlab.ur``: a cursor over the bytes, like the library's ``BinParser``, that reads one
big-endian field at a time and refuses to read past its end.
"""

import struct


class Cursor:
    """The Client Library's BinParser: big-endian fields read in order within [pos, end)."""

    def __init__(self, data, pos=0, end=None):
        self.data, self.pos = data, pos
        self.end = len(data) if end is None else end

    def take(self, fmt):
        size = struct.calcsize(">" + fmt)
        if self.pos + size > self.end:
            raise ValueError(f"could not parse: {size} bytes wanted at {self.pos}, "
                             f"{self.end - self.pos} left")
        values = struct.unpack_from(">" + fmt, self.data, self.pos)
        self.pos += size
        return values if len(values) > 1 else values[0]

    def rest(self):
        out, self.pos = self.data[self.pos:self.end], self.end
        return out


def messages(stream):
    """Split bytes into whole messages (int32 size, header included; uint8 type)."""
    out, pos = [], 0
    while pos + 5 <= len(stream):
        size = struct.unpack_from(">i", stream, pos)[0]
        if size < 5 or pos + size > len(stream):
            break
        out.append(stream[pos:pos + size])
        pos += size
    return out, stream[pos:]


def decode(message):
    """One message as a dict: {"type": 16, "packages": {type: fields}} for a robot state (the
    first sub-package of each type), {"type": 20, "version": ...} for a version message."""
    c = Cursor(message)
    c.take("i")
    kind = c.take("B")
    if kind == 20:
        c.take("Q")                                          # timestamp
        c.take("B")                                          # source
        if c.take("B") != 3:
            return {"type": 20}
        name = c.rest()
        c = Cursor(name)
        n = c.take("b")
        project = bytes(c.data[c.pos:c.pos + n]).decode()
        c.pos += n
        major, minor, svn, build = c.take("B"), c.take("B"), c.take("i"), c.take("i")
        return {"type": 20, "version": (project, major, minor, svn, build,
                                        bytes(c.rest()).decode())}
    if kind != 16:
        return {"type": kind}
    packages = {}
    while c.pos < c.end:
        size = struct.unpack_from(">I", c.data, c.pos)[0]
        sub = Cursor(c.data, c.pos, c.pos + size)
        c.pos += size
        sub.take("I")
        ptype = sub.take("B")
        if ptype in packages:
            continue
        if ptype == 0:
            names = ("timestamp", "connected", "enabled", "power_on", "emergency_stopped",
                     "protective_stopped", "program_running", "program_paused", "robot_mode",
                     "control_mode", "target_speed_fraction", "speed_scaling",
                     "target_speed_fraction_limit")
            fmts = "Q???????BBddd"
            packages[0] = {k: sub.take(f) for k, f in zip(names, fmts, strict=True)}
        elif ptype == 1:
            joints = [sub.take("dddffffB") for _ in range(6)]
            packages[1] = {"q_actual": [j[0] for j in joints], "qd_actual": [j[2] for j in joints],
                           "joint_mode": [j[7] for j in joints]}
        elif ptype == 4:
            packages[4] = {"tcp_pose": list(sub.take("6d")), "tcp_offset": list(sub.take("6d"))}
        elif ptype == 5:
            packages[5] = {"checksum": list(sub.take("6I")), "dh_theta": list(sub.take("6d")),
                           "dh_a": list(sub.take("6d")), "dh_d": list(sub.take("6d")),
                           "dh_alpha": list(sub.take("6d")), "calibration_status": sub.take("I")}
    return {"type": 16, "packages": packages}
