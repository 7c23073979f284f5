"""Write dqlab/_fast/newton_lanes.py: the Newton steps of the calibrated UR solver on eight
branches at once, as straight-line code (generated, so that the compiler vectorises it
across the branches).

    python tools/generate_newton_lanes.py          # rewrite the file
    python tools/generate_newton_lanes.py --check  # exit 1 if the file is not up to date

Each generated function loops over the W branches (lanes) of a scratch array S in which
variable v of lane r is ``S[v * W + r]``: one array with constant offsets, which the
compiler can prove independent and turn into vector instructions. The formulas are those
of ``dqlab._fast.newton_compiled`` (and of the numpy path of ``dqlab.ik.ur_calibrated``),
written out entry by entry in the same order of operations.
"""

import sys
from pathlib import Path

TARGET = Path(__file__).resolve().parents[1] / "dqlab" / "_fast" / "newton_lanes.py"
W = 8

# the variables of a lane, in S
LAYOUT = ([f"q{i}" for i in range(6)] + [f"c{i}" for i in range(6)]
          + [f"s{i}" for i in range(6)]
          + [f"t{i}{j}" for i in range(3) for j in range(3)] + [f"tp{i}" for i in range(3)]
          + [f"F{k}" for k in range(48)] + [f"x{i}" for i in range(6)] + ["act", "size"]
          + [f"g{i}" for i in range(6)])          # grad log m of a deflated step
INDEX = {name: k for k, name in enumerate(LAYOUT)}


def at(name):
    """The entry of S that holds variable ``name`` of lane r."""
    return f"S[{INDEX[name] * W} + r]"


def frames():
    """Frames of the chain from the cosines and sines of the joint angles (as
    ``newton_compiled._frames``, the tool always applied)."""
    head = ["def frames(S, L, T):",
            '    """The frames F (48 entries, ``EntryChain``\'s layout) of every lane from its',
            '    cosines and sines: links L (6, 5) as (cos alpha, sin alpha, a, d, theta0),',
            '    tool T (4, 4)."""']
    for i in range(6):
        head.append(f"    ca{i}, sa{i}, a{i}, d{i} = L[{i}, 0], L[{i}, 1], L[{i}, 2], L[{i}, 3]")
    for i in range(3):
        head.append(f"    T{i}0, T{i}1, T{i}2, T{i}3 = T[{i}, 0], T[{i}, 1], T[{i}, 2], T[{i}, 3]")
    b = ["c = " + at("c0"), "s = " + at("s0"),
         "x0 = c", "x1 = s", "x2 = 0.0",
         "y0 = -ca0 * s", "y1 = ca0 * c", "y2 = sa0",
         "z0 = sa0 * s", "z1 = -sa0 * c", "z2 = ca0",
         "o0 = a0 * c", "o1 = a0 * s", "o2 = d0"]
    b += [f"{at(f'F{k}')} = z{k}" for k in range(3)]
    b += [f"{at(f'F{15 + k}')} = o{k}" for k in range(3)]
    for i in range(1, 6):
        b += [f"c = {at(f'c{i}')}", f"s = {at(f's{i}')}"]
        b += [f"n{k} = c * x{k} + s * y{k}" for k in range(3)]
        b += [f"p{k} = c * y{k} - s * x{k}" for k in range(3)]
        b += [f"o{k} = o{k} + d{i} * z{k} + a{i} * n{k}" for k in range(3)]
        b += [f"y{k} = ca{i} * p{k} + sa{i} * z{k}" for k in range(3)]
        b += [f"z{k} = ca{i} * z{k} - sa{i} * p{k}" for k in range(3)]
        b += [f"x{k} = n{k}" for k in range(3)]
        if i < 5:
            b += [f"{at(f'F{3 * i + k}')} = z{k}" for k in range(3)]
            b += [f"{at(f'F{15 + 3 * i + k}')} = o{k}" for k in range(3)]
        if i in (1, 2):
            b += [f"{at(f'F{27 + 3 * i + k}')} = x{k}" for k in range(3)]
    b += [f"{at(f'F{36 + k}')} = o{k} + T03 * x{k} + T13 * y{k} + T23 * z{k}"
          for k in range(3)]
    b += [f"{at(f'F{39 + 3 * k + j}')} = x{k} * T0{j} + y{k} * T1{j} + z{k} * T2{j}"
          for k in range(3) for j in range(3)]
    return head + [f"    for r in range({W}):"] + ["        " + line for line in b]


# sin and cos: the angle reduced by multiples of pi/2 (Cody and Waite, pi/2 in three parts of
# which the first two have 33 significant bits, so that k times them is exact), then the
# polynomials of fdlibm's __kernel_sin and __kernel_cos on [-pi/4, pi/4]
PIO2 = ("1.57079632673412561417e+00", "6.07710050630396597660e-11",
        "2.02226624879595063154e-21")
SIN = ("-1.66666666666666324348e-01", "8.33333333332248946124e-03",
       "-1.98412698298579493134e-04", "2.75573137070700676789e-06",
       "-2.50507602534068634195e-08", "1.58969099521155010221e-10")
COS = ("4.16666666666666019037e-02", "-1.38888888888741095749e-03",
       "2.48015872894767294178e-05", "-2.75573143513906633035e-07",
       "2.08757232129817482790e-09", "-1.13596475577881948265e-11")


def horner(coefficients):
    """c0 + z (c1 + z (c2 + ...)) as text."""
    text = coefficients[-1]
    for c in reversed(coefficients[:-1]):
        text = f"{c} + z * ({text})"
    return text


def angles(recompute=False):
    """The cosines and sines of the joint angles q + theta0 of every lane; with
    ``recompute``, only of the joints whose last step was 0.02 rad or more (or not a
    number), the others keeping the values their step turned."""
    if recompute:
        head = ["def recompute(S, L):",
                '    """c and s of the joints whose step x_i was 0.02 rad or more (or not a',
                "    number), from their new angle as angles computes them; the others keep the",
                '    values the step turned (its Taylor series is for short steps)."""']
    else:
        head = ["def angles(S, L):",
                '    """c and s of every lane: the cosine and sine of q_i + theta0_i (the angle',
                "    reduced by multiples of pi/2, then fdlibm's polynomials; within an ulp or two",
                '    of the library functions)."""']
    head += [f"    t{i} = L[{i}, 4]" for i in range(6)]
    b = []
    for i in range(6):
        c, s = at(f"c{i}"), at(f"s{i}")
        long_step = f"not abs({at(f'x{i}')}) < 0.02"
        b += [f"x = {at(f'q{i}')} + t{i}",
              "k = np.rint(x * 0.6366197723675814)",
              f"u = ((x - k * {PIO2[0]}) - k * {PIO2[1]}) - k * {PIO2[2]}",
              "z = u * u",
              f"sn = u + u * z * ({horner(SIN)})",
              f"cn = 1.0 - 0.5 * z + z * z * ({horner(COS)})",
              "m = k - 4.0 * np.floor(0.25 * k)",
              f"{c} = (cn if m == 0.0 else (-sn if m == 1.0 else "
              f"(-cn if m == 2.0 else sn)))" + (f" if {long_step} else {c}" if recompute else ""),
              f"{s} = (sn if m == 0.0 else (cn if m == 1.0 else "
              f"(-sn if m == 2.0 else -cn)))" + (f" if {long_step} else {s}" if recompute else "")]
    return head + [f"    for r in range({W}):"] + ["        " + line for line in b]


def residual():
    """e0..e5 as locals: position error and half the skew part of R* R^T."""
    b = [f"e{k} = {at(f'tp{k}')} - {at(f'F{36 + k}')}" for k in range(3)]
    for k, (i, j) in enumerate(((2, 1), (0, 2), (1, 0))):
        tr_i = " + ".join(f"{at(f't{i}{c}')} * {at(f'F{39 + 3 * j + c}')}" for c in range(3))
        tr_j = " + ".join(f"{at(f't{j}{c}')} * {at(f'F{39 + 3 * i + c}')}" for c in range(3))
        b.append(f"e{3 + k} = 0.5 * (({tr_i}) - ({tr_j}))")
    return b


def step(deflated=False):
    """The damped Newton step of every active lane, shortened; q and the cosines and sines
    turned by it (Taylor series; steps of 0.02 rad or more are left for the caller).
    ``deflated``: the step of deflated Newton instead, x / (1 - g . x) for the lane's
    grad log m in g (``dqlab.ik.ur_calibrated._deflated_newton``)."""
    if deflated:
        head = ["def deflated_step(S, damping, max_step):",
                '    """One deflated Newton step of every lane whose ``act`` is not 0 (the step',
                '    of the others is 0): x of :func:`step` divided by 1 - g . x, g the',
                "    lane's grad log m; an entry not finite made 0; shortened to max_step, then q",
                '    and (c, s) turned by it as :func:`step` does. A lane whose Cholesky',
                '    fails (x not a number) takes no step and gets ``act`` -1."""']
    else:
        head = ["def step(S, damping, max_step):",
                '    """One damped Newton step of every lane whose ``act`` is not 0 (the step of',
                '    the others is 0): x = (J^T J + lambda I)^-1 J^T e by Cholesky, shortened to',
                '    max_step, then q += x and (c, s) turned by x (Taylor series to x^7; the',
                '    caller recomputes the joints whose step is 0.02 rad or more)."""']
    b = residual()
    b += ["px = " + at("F36"), "py = " + at("F37"), "pz = " + at("F38")]
    b += ["J00 = -py", "J01 = px", "J02 = 0.0", "J03 = 0.0", "J04 = 0.0", "J05 = 1.0"]
    for i in range(5):
        j = i + 1
        b += [f"zx = {at(f'F{3 * i}')}", f"zy = {at(f'F{3 * i + 1}')}",
              f"zz = {at(f'F{3 * i + 2}')}",
              f"rx = px - {at(f'F{15 + 3 * i}')}", f"ry = py - {at(f'F{16 + 3 * i}')}",
              f"rz = pz - {at(f'F{17 + 3 * i}')}",
              f"J{j}0 = zy * rz - zz * ry", f"J{j}1 = zz * rx - zx * rz",
              f"J{j}2 = zx * ry - zy * rx", f"J{j}3 = zx", f"J{j}4 = zy", f"J{j}5 = zz"]
    b.append("trace = 0.0")
    for i in range(6):
        for j in range(i + 1):
            b.append(f"H{i}{j} = 0.0 + " + " + ".join(f"J{i}{k} * J{j}{k}" for k in range(6)))
        b.append(f"trace = trace + H{i}{i}")
        b.append(f"g{i} = 0.0 + " + " + ".join(f"J{i}{k} * e{k}" for k in range(6)))
    b.append("lam = (damping / 6.0) * trace")
    b += [f"H{i}{i} = H{i}{i} + lam" for i in range(6)]
    for j in range(6):
        b.append(f"v = H{j}{j}" + "".join(f" - H{j}{k} * H{j}{k}" for k in range(j)))
        b.append(f"H{j}{j} = math.sqrt(v)")
        b.append(f"inv{j} = 1.0 / H{j}{j}")
        for i in range(j + 1, 6):
            b.append(f"H{i}{j} = (H{i}{j}" + "".join(f" - H{i}{k} * H{j}{k}" for k in range(j))
                     + f") * inv{j}")
    for i in range(6):
        b.append(f"g{i} = (g{i}" + "".join(f" - H{i}{k} * g{k}" for k in range(i))
                 + f") * inv{i}")
    for i in range(5, -1, -1):
        b.append(f"x{i} = (g{i}" + "".join(f" - H{k}{i} * x{k}" for k in range(i + 1, 6))
                 + f") * inv{i}")
    b.append("nan = " + " | ".join(f"(x{i} != x{i})" for i in range(6)))
    if deflated:
        b.append("scale = 1.0 - (0.0 + " + " + ".join(f"{at(f'g{i}')} * x{i}" for i in range(6))
                 + ")")
        for i in range(6):
            b += [f"x{i} = x{i} / scale", f"x{i} = x{i} if abs(x{i}) < math.inf else 0.0"]
    b.append("longest = " + "max(" * 5 + "abs(x0)" + "".join(f", abs(x{i}))"
                                                           for i in range(1, 6)))
    if deflated:
        b.append("factor = min(1.0, max_step / max(longest, 1e-300))")
        b.append(f"{at('act')} = -1.0 if nan else {at('act')}")
        b.append(f"moving = {at('act')} > 0.0")
    else:
        b.append("factor = math.nan if nan else min(1.0, max_step / max(longest, 1e-300))")
        b.append(f"moving = {at('act')} != 0.0")
    for i in range(6):
        b += [f"d = x{i} * factor if moving else 0.0",
              f"{at(f'x{i}')} = d",
              f"{at(f'q{i}')} = {at(f'q{i}')} + d",
              "d2 = d * d",
              "cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)))",
              "sd = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 * (1.0 / 5040.0))))",
              f"c = {at(f'c{i}')}", f"s = {at(f's{i}')}",
              f"{at(f'c{i}')} = c * cd - s * sd",
              f"{at(f's{i}')} = s * cd + c * sd"]
    return head + [f"    for r in range({W}):"] + ["        " + line for line in b]


def size():
    """The size of every lane's error, into ``size``."""
    head = ["def size(S):",
            '    """The larger of the position and rotation errors (Euclidean) of every lane."""']
    b = residual()
    b.append(f"{at('size')} = math.sqrt(max(e0 * e0 + e1 * e1 + e2 * e2, "
             "e3 * e3 + e4 * e4 + e5 * e5))")
    return head + [f"    for r in range({W}):"] + ["        " + line for line in b]


def source():
    lines = ["# ruff: noqa: E501",
             '"""Generated by tools/generate_newton_lanes.py: do not edit (the generator says',
             "what it writes and why).",
             "",
             "The Newton steps of ``dqlab._fast.newton_compiled`` on W branches at once (lanes),",
             "straight-line, variable v of lane r in ``S[v * W + r]``.",
             '"""',
             "",
             "import math",
             "",
             "import numpy as np",
             "",
             f"W = {W}",
             f"NV = {len(LAYOUT)}",
             "#: where each variable of a lane lives in S (times W)",
             "INDEX = {" + ", ".join(f'"{k}": {v}' for k, v in INDEX.items()) + "}",
             "", ""]
    for f in (angles, lambda: angles(recompute=True), frames, step,
              lambda: step(deflated=True), size):
        lines += f() + ["", ""]
    return "\n".join(lines).rstrip() + "\n"


def main(argv):
    text = source()
    if "--check" in argv:
        if not TARGET.exists() or TARGET.read_text() != text:
            print(f"{TARGET} is not up to date: run python tools/generate_newton_lanes.py")
            return 1
        return 0
    TARGET.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
