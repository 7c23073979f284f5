"""The speed machinery of :mod:`dqlab.dynamics`: Newton--Euler for one state on Python floats.

The same recursion as :func:`dqlab.dynamics.inverse_dynamics` (its module docstring), written
with rotation matrices and vectors of Python floats instead of dual-quaternion sandwiches on
numpy arrays: for one joint vector, numpy's cost per call dominates, and this path is about
fifty times faster. The adjoint of a dual quaternion is its rotation and a cross product,

    Q* (w + eps v) Q = R^T w + eps R^T (v + w x p),    Q (f + eps n) Q* = R f + eps (R n + p x R f),

for the pose (R, p) of frame i in frame i-1. The tests check this path against the readable
one on random states of every model.
"""

import math


def constants(robot, inertias, twists, g_0):
    """Everything of ``robot`` the recursion reads, as Python floats: per link the DH
    parameters, the joint twist (``twists``, shape (n, 2, 3)) and the inertia; and gravity in
    frame 0."""
    links = []
    for link, s, inertia in zip(robot.links, twists, inertias, strict=True):
        (ixx, ixy, ixz), (_, iyy, iyz), (_, _, izz) = inertia.tensor.tolist()
        links.append((link.is_revolute, link.theta_offset, link.d, link.a,
                      math.cos(link.alpha), math.sin(link.alpha),
                      tuple(s[0].tolist()), tuple(s[1].tolist()), inertia.mass,
                      tuple(inertia.com.tolist()), (ixx, iyy, izz, ixy, ixz, iyz)))
    return robot.convention == "dh", links, tuple(float(x) for x in g_0)


def inverse_dynamics(consts, q, qd, qdd):
    """Joint torques (a list of floats) for one state given as lists of floats.

    Every vector is written out in its three components (``wx, wy, wz`` for the angular
    velocity, ``vx...`` for the velocity of the body point at the frame's origin, ``ax...``
    and ``bx...`` for their rates), which is what makes this path fast.
    """
    standard, links, (gx, gy, gz) = consts
    wx = wy = wz = vx = vy = vz = 0.0                  # the base at rest
    ax = ay = az = 0.0                                 # its angular acceleration
    bx, by, bz = -gx, -gy, -gz                         # rising at -g: gravity
    poses, wrenches = [], []
    for (revolute, theta0, d0, a, ca, sa, (sx, sy, sz), (tx, ty, tz), m, (cx, cy, cz),
         (ixx, iyy, izz, ixy, ixz, iyz)), q_i, qd_i, qdd_i in zip(links, q, qd, qdd,
                                                                  strict=True):
        if revolute:
            theta, d = q_i + theta0, d0
        else:
            theta, d = theta0, q_i + d0
        ct, st = math.cos(theta), math.sin(theta)
        if standard:       # Rz(theta) Tz(d) Tx(a) Rx(alpha)
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = (ct, -st * ca, st * sa, st,
                                                           ct * ca, -ct * sa, 0.0, sa, ca)
            px, py, pz = a * ct, a * st, d
        else:              # Rx(alpha) Tx(a) Rz(theta) Tz(d)
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = (ct, -st, 0.0, ca * st, ca * ct,
                                                           -sa, sa * st, sa * ct, ca)
            px, py, pz = a, -sa * d, ca * d
        poses.append((r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz))
        # into frame i: w' = R^T w, v' = R^T (v + w x p); the same for the rates
        ux, uy, uz = vx + wy * pz - wz * py, vy + wz * px - wx * pz, vz + wx * py - wy * px
        wx, wy, wz = (r00 * wx + r10 * wy + r20 * wz, r01 * wx + r11 * wy + r21 * wz,
                      r02 * wx + r12 * wy + r22 * wz)
        vx, vy, vz = (r00 * ux + r10 * uy + r20 * uz, r01 * ux + r11 * uy + r21 * uz,
                      r02 * ux + r12 * uy + r22 * uz)
        ux, uy, uz = bx + ay * pz - az * py, by + az * px - ax * pz, bz + ax * py - ay * px
        ax, ay, az = (r00 * ax + r10 * ay + r20 * az, r01 * ax + r11 * ay + r21 * az,
                      r02 * ax + r12 * ay + r22 * az)
        bx, by, bz = (r00 * ux + r10 * uy + r20 * uz, r01 * ux + r11 * uy + r21 * uz,
                      r02 * ux + r12 * uy + r22 * uz)
        # plus the joint's own twist s qd, and its rate s qdd + xi x s qd
        wx, wy, wz = wx + sx * qd_i, wy + sy * qd_i, wz + sz * qd_i
        vx, vy, vz = vx + tx * qd_i, vy + ty * qd_i, vz + tz * qd_i
        ex, ey, ez = sx * qd_i, sy * qd_i, sz * qd_i          # s qd, real part
        fx, fy, fz = tx * qd_i, ty * qd_i, tz * qd_i          # and dual part
        ax, ay, az = (ax + sx * qdd_i + wy * ez - wz * ey, ay + sy * qdd_i + wz * ex - wx * ez,
                      az + sz * qdd_i + wx * ey - wy * ex)
        bx, by, bz = (bx + tx * qdd_i + wy * fz - wz * fy + vy * ez - vz * ey,
                      by + ty * qdd_i + wz * fx - wx * fz + vz * ex - vx * ez,
                      bz + tz * qdd_i + wx * fy - wy * fx + vx * ey - vy * ex)
        # momentum h = (p, L), p = m (v + w x c), L = I_c w + c x p, and its rate's part
        # M xi_dot, the same formula on (a, b)
        pxm = m * (vx + wy * cz - wz * cy)
        pym = m * (vy + wz * cx - wx * cz)
        pzm = m * (vz + wx * cy - wy * cx)
        Lx = ixx * wx + ixy * wy + ixz * wz + cy * pzm - cz * pym
        Ly = ixy * wx + iyy * wy + iyz * wz + cz * pxm - cx * pzm
        Lz = ixz * wx + iyz * wy + izz * wz + cx * pym - cy * pxm
        qx = m * (bx + ay * cz - az * cy)
        qy = m * (by + az * cx - ax * cz)
        qz = m * (bz + ax * cy - ay * cx)
        Nx = ixx * ax + ixy * ay + ixz * az + cy * qz - cz * qy
        Ny = ixy * ax + iyy * ay + iyz * az + cz * qx - cx * qz
        Nz = ixz * ax + iyz * ay + izz * az + cx * qy - cy * qx
        # the net wrench M xi_dot + xi x M xi: f = p_dot + w x p, n = L_dot + w x L + v x p
        wrenches.append((qx + wy * pzm - wz * pym, qy + wz * pxm - wx * pzm,
                         qz + wx * pym - wy * pxm,
                         Nx + wy * Lz - wz * Ly + vy * pzm - vz * pym,
                         Ny + wz * Lx - wx * Lz + vz * pxm - vx * pzm,
                         Nz + wx * Ly - wy * Lx + vx * pym - vy * pxm))
    n_links = len(links)
    tau = [0.0] * n_links
    fx = fy = fz = nx = ny = nz = 0.0
    for i in range(n_links - 1, -1, -1):
        if i < n_links - 1:      # carried from frame i+1 into frame i: R f, R n + p x R f
            r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = poses[i + 1]
            fx, fy, fz = (r00 * fx + r01 * fy + r02 * fz, r10 * fx + r11 * fy + r12 * fz,
                          r20 * fx + r21 * fy + r22 * fz)
            nx, ny, nz = (r00 * nx + r01 * ny + r02 * nz + py * fz - pz * fy,
                          r10 * nx + r11 * ny + r12 * nz + pz * fx - px * fz,
                          r20 * nx + r21 * ny + r22 * nz + px * fy - py * fx)
        f0, f1, f2, n0, n1, n2 = wrenches[i]
        fx, fy, fz, nx, ny, nz = fx + f0, fy + f1, fz + f2, nx + n0, ny + n1, nz + n2
        _, _, _, _, _, _, (sx, sy, sz), (tx, ty, tz), _, _, _ = links[i]
        tau[i] = nx * sx + ny * sy + nz * sz + fx * tx + fy * ty + fz * tz
    return tau
