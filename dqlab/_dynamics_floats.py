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


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _momentum(m, c, inertia, w, v):
    """p = m (v + w x c), L = I_c w + c x p."""
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    wc = _cross(w, c)
    p = (m * (v[0] + wc[0]), m * (v[1] + wc[1]), m * (v[2] + wc[2]))
    cp = _cross(c, p)
    return p, (ixx * w[0] + ixy * w[1] + ixz * w[2] + cp[0],
               ixy * w[0] + iyy * w[1] + iyz * w[2] + cp[1],
               ixz * w[0] + iyz * w[1] + izz * w[2] + cp[2])


def inverse_dynamics(consts, q, qd, qdd):
    """Joint torques (a list of floats) for one state given as lists of floats."""
    standard, links, g_0 = consts
    w, v = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    w_dot, v_dot = (0.0, 0.0, 0.0), (-g_0[0], -g_0[1], -g_0[2])
    poses, wrenches = [], []
    for (revolute, theta0, d0, a, ca, sa, s_w, s_v, m, c, inertia), q_i, qd_i, qdd_i in zip(
            links, q, qd, qdd, strict=True):
        if revolute:
            theta, d = q_i + theta0, d0
        else:
            theta, d = theta0, q_i + d0
        ct, st = math.cos(theta), math.sin(theta)
        if standard:       # Rz(theta) Tz(d) Tx(a) Rx(alpha)
            R = ((ct, -st * ca, st * sa), (st, ct * ca, -ct * sa), (0.0, sa, ca))
            p = (a * ct, a * st, d)
        else:              # Rx(alpha) Tx(a) Rz(theta) Tz(d)
            R = ((ct, -st, 0.0), (ca * st, ca * ct, -sa), (sa * st, sa * ct, ca))
            p = (a, -sa * d, ca * d)
        poses.append((R, p))
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
        # the twist and its rate carried into frame i: R^T w, R^T (v + w x p)
        for_twist = []
        for x, y in ((w, v), (w_dot, v_dot)):
            u = _cross(x, p)
            u = (y[0] + u[0], y[1] + u[1], y[2] + u[2])
            for_twist.append(((r00 * x[0] + r10 * x[1] + r20 * x[2],
                               r01 * x[0] + r11 * x[1] + r21 * x[2],
                               r02 * x[0] + r12 * x[1] + r22 * x[2]),
                              (r00 * u[0] + r10 * u[1] + r20 * u[2],
                               r01 * u[0] + r11 * u[1] + r21 * u[2],
                               r02 * u[0] + r12 * u[1] + r22 * u[2])))
        (w, v), (w_dot, v_dot) = for_twist
        w = (w[0] + s_w[0] * qd_i, w[1] + s_w[1] * qd_i, w[2] + s_w[2] * qd_i)
        v = (v[0] + s_v[0] * qd_i, v[1] + s_v[1] * qd_i, v[2] + s_v[2] * qd_i)
        sw = (s_w[0] * qd_i, s_w[1] * qd_i, s_w[2] * qd_i)
        sv = (s_v[0] * qd_i, s_v[1] * qd_i, s_v[2] * qd_i)
        turn = _cross(w, sw)
        slide_a, slide_b = _cross(w, sv), _cross(v, sw)
        w_dot = (w_dot[0] + s_w[0] * qdd_i + turn[0], w_dot[1] + s_w[1] * qdd_i + turn[1],
                 w_dot[2] + s_w[2] * qdd_i + turn[2])
        v_dot = (v_dot[0] + s_v[0] * qdd_i + slide_a[0] + slide_b[0],
                 v_dot[1] + s_v[1] * qdd_i + slide_a[1] + slide_b[1],
                 v_dot[2] + s_v[2] * qdd_i + slide_a[2] + slide_b[2])
        p_, L = _momentum(m, c, inertia, w, v)
        p_dot, L_dot = _momentum(m, c, inertia, w_dot, v_dot)
        wp, wL, vp = _cross(w, p_), _cross(w, L), _cross(v, p_)
        wrenches.append(((p_dot[0] + wp[0], p_dot[1] + wp[1], p_dot[2] + wp[2]),
                         (L_dot[0] + wL[0] + vp[0], L_dot[1] + wL[1] + vp[1],
                          L_dot[2] + wL[2] + vp[2])))
    n_links = len(links)
    tau = [0.0] * n_links
    f, n = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    for i in range(n_links - 1, -1, -1):
        if i < n_links - 1:      # carried from frame i+1 into frame i: R f, R n + p x R f
            (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = poses[i + 1][0]
            p = poses[i + 1][1]
            f = (r00 * f[0] + r01 * f[1] + r02 * f[2], r10 * f[0] + r11 * f[1] + r12 * f[2],
                 r20 * f[0] + r21 * f[1] + r22 * f[2])
            n = (r00 * n[0] + r01 * n[1] + r02 * n[2], r10 * n[0] + r11 * n[1] + r12 * n[2],
                 r20 * n[0] + r21 * n[1] + r22 * n[2])
            pf = _cross(p, f)
            n = (n[0] + pf[0], n[1] + pf[1], n[2] + pf[2])
        (f_i, n_i) = wrenches[i]
        f = (f[0] + f_i[0], f[1] + f_i[1], f[2] + f_i[2])
        n = (n[0] + n_i[0], n[1] + n_i[1], n[2] + n_i[2])
        s_w, s_v = links[i][6], links[i][7]
        tau[i] = (n[0] * s_w[0] + n[1] * s_w[1] + n[2] * s_w[2]
                  + f[0] * s_v[0] + f[1] * s_v[1] + f[2] * s_v[2])
    return tau
