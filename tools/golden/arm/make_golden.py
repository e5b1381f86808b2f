#!/usr/bin/env python3
# Regenerate crates/oddball-arm/tests/fixtures/arm_golden.json (from the repository root):
#   python3 -m venv /tmp/v && /tmp/v/bin/pip install -r tools/golden/arm/requirements.txt \
#       && /tmp/v/bin/python tools/golden/arm/make_golden.py
"""Golden values for the oddball-arm dynamics, from an independent symbolic derivation.

Derives the planar two-link arm's equations of motion from the Lagrangian with sympy (no
closed forms copied from the Rust code): kinetic energy from the centre-of-mass velocities and
link rotation rates, potential energy from the centre-of-mass heights, M as the Hessian of the
kinetic energy in the joint rates, C from the Christoffel symbols of M, g as the gradient of the
potential, and checks symbolically that  d/dt ∂L/∂θ̇ − ∂L/∂θ = M θ̈ + C θ̇ + g.  It then
evaluates, at fixed (θ, θ̇, θ̈) states and with 30-digit arithmetic, the pen position, the
analytical Jacobian J_A, its time derivative J̇_A, M, C, g and the inverse-dynamics torque
u = M θ̈ + C θ̇ + g + B θ̇ (B = diagonal viscous friction), and writes them to
crates/oddball-arm/tests/fixtures/arm_golden.json, which the Rust test `golden` compares to 1e-9.

Conventions (as in the crate): x horizontal, z vertical up, gravity along −z, shoulder at the
base point; θ1 from +x towards +z; θ2 relative to link 1; centres of mass on the links.

Run from the repository root:

    python3 -m venv /tmp/v && /tmp/v/bin/pip install -r tools/golden/arm/requirements.txt \
        && /tmp/v/bin/python tools/golden/arm/make_golden.py

The parameters below are the crate's defaults except for the base point, gravity and friction,
which are set to non-default values so the test exercises them; the fixture stores them and the
Rust test builds its model from the fixture.
"""

import json
import pathlib

import numpy as np
import sympy as sp

ROOT = pathlib.Path(__file__).resolve().parents[3]
OUT = ROOT / "crates" / "oddball-arm" / "tests" / "fixtures" / "arm_golden.json"

PARAMS = {
    "l1": "0.30",
    "l2": "0.25",
    "m1": "1.2",
    "m2": "0.8",
    "lc1": "0.15",
    "lc2": "0.125",
    # slender rods: m l^2 / 12
    "I1": "0.009",
    "I2": str(sp.Rational(8, 10) * sp.Rational(25, 100) ** 2 / 12),
    "b1": "0.05",
    "b2": "0.03",
    "g": "9.80665",
    "base_x": "0.013",
    "base_z": "-0.021",
}

# Fixed states (θ1, θ2), (θ̇1, θ̇2), (θ̈1, θ̈2): rest, typical drawing poses, fast motions, and
# configurations near the stretched and folded singularities.
STATES = [
    ((0.0, 0.0), (0.0, 0.0), (0.0, 0.0)),
    ((0.6, -1.2), (0.0, 0.0), (0.0, 0.0)),
    ((0.6, -1.2), (0.4, -0.7), (1.5, -2.0)),
    ((1.1, -2.1), (-1.3, 2.2), (-4.0, 3.5)),
    ((-0.4, 0.9), (2.5, -3.0), (10.0, -12.0)),
    ((1.5707963267948966, -0.3), (0.1, 0.2), (0.3, 0.4)),
    ((2.2, -2.7), (-0.6, -0.9), (0.0, 7.0)),
    ((-1.3, 1.7), (3.0, 4.0), (-20.0, 15.0)),
    ((0.25, -0.02), (0.05, -5.0), (2.0, 2.0)),
    ((3.0, 2.9), (-2.0, 1.0), (5.0, -5.0)),
    ((0.9, -1.6), (7.0, -9.0), (-30.0, 40.0)),
]


def derive():
    t = sp.symbols("t")
    l1, l2, m1, m2, lc1, lc2, I1, I2, b1, b2, g, bx, bz = sp.symbols(
        "l1 l2 m1 m2 lc1 lc2 I1 I2 b1 b2 g base_x base_z", real=True
    )
    th1 = sp.Function("th1")(t)
    th2 = sp.Function("th2")(t)
    q = sp.Matrix([th1, th2])
    qd = q.diff(t)
    qdd = qd.diff(t)

    # Centre-of-mass positions in the x–z plane.
    p1 = sp.Matrix([bx + lc1 * sp.cos(th1), bz + lc1 * sp.sin(th1)])
    p2 = sp.Matrix(
        [
            bx + l1 * sp.cos(th1) + lc2 * sp.cos(th1 + th2),
            bz + l1 * sp.sin(th1) + lc2 * sp.sin(th1 + th2),
        ]
    )
    pen = sp.Matrix(
        [
            bx + l1 * sp.cos(th1) + l2 * sp.cos(th1 + th2),
            bz + l1 * sp.sin(th1) + l2 * sp.sin(th1 + th2),
        ]
    )
    v1 = p1.diff(t)
    v2 = p2.diff(t)
    w1 = qd[0]
    w2 = qd[0] + qd[1]
    T = sp.Rational(1, 2) * (m1 * v1.dot(v1) + I1 * w1**2 + m2 * v2.dot(v2) + I2 * w2**2)
    V = m1 * g * p1[1] + m2 * g * p2[1]
    L = T - V

    # Replace the functions of t by plain symbols for differentiation by q and q̇.
    Q1, Q2, W1, W2, A1, A2 = sp.symbols("Q1 Q2 W1 W2 A1 A2", real=True)
    subs = [(qdd[0], A1), (qdd[1], A2), (qd[0], W1), (qd[1], W2), (th1, Q1), (th2, Q2)]
    Qs = [Q1, Q2]
    Ws = [W1, W2]

    Ts = sp.simplify(T.subs(subs))
    Vs = V.subs(subs)
    M = sp.Matrix(2, 2, lambda i, j: sp.simplify(sp.diff(Ts, Ws[i], Ws[j])))
    # Christoffel symbols of the first kind: C_kj = sum_i c_ijk(q) q̇_i,
    # c_ijk = 1/2 (∂M_kj/∂q_i + ∂M_ki/∂q_j − ∂M_ij/∂q_k).
    C = sp.zeros(2, 2)
    for k in range(2):
        for j in range(2):
            C[k, j] = sp.simplify(
                sum(
                    sp.Rational(1, 2)
                    * (sp.diff(M[k, j], Qs[i]) + sp.diff(M[k, i], Qs[j]) - sp.diff(M[i, j], Qs[k]))
                    * Ws[i]
                    for i in range(2)
                )
            )
    G = sp.Matrix([sp.simplify(sp.diff(Vs, Qs[i])) for i in range(2)])

    # Check against the Euler–Lagrange equations computed directly from L(q(t), q̇(t)).
    el = sp.Matrix(
        [sp.diff(sp.diff(L, qd[i]), t) - sp.diff(L, q[i]) for i in range(2)]
    ).subs(subs)
    residual = sp.simplify(el - (M * sp.Matrix([A1, A2]) + C * sp.Matrix([W1, W2]) + G))
    assert residual == sp.zeros(2, 1), f"Euler–Lagrange mismatch: {residual}"

    pen_s = pen.subs(subs)
    J = pen_s.jacobian([Q1, Q2])
    # J̇ = Σ_i ∂J/∂q_i q̇_i
    Jdot = sp.simplify(J.diff(Q1) * W1 + J.diff(Q2) * W2)
    B = sp.diag(b1, b2)
    tau = M * sp.Matrix([A1, A2]) + C * sp.Matrix([W1, W2]) + G + B * sp.Matrix([W1, W2])

    syms = dict(
        l1=l1, l2=l2, m1=m1, m2=m2, lc1=lc1, lc2=lc2, I1=I1, I2=I2, b1=b1, b2=b2, g=g,
        base_x=bx, base_z=bz,
    )
    return syms, (Q1, Q2, W1, W2, A1, A2), dict(pen=pen_s, J=J, Jdot=Jdot, M=M, C=C, g=G, tau=tau)


def exact(text):
    """A parameter given as decimal text, as an exact rational (no binary rounding)."""
    return sp.Rational(text)


def to_list(expr, values):
    mat = sp.Matrix(expr).evalf(30, subs=values)
    arr = np.array(mat.tolist(), dtype=np.float64)
    return arr.reshape(mat.shape).tolist() if mat.shape[1] > 1 else arr.reshape(-1).tolist()


def main():
    syms, (Q1, Q2, W1, W2, A1, A2), exprs = derive()
    param_values = {syms[k]: exact(v) for k, v in PARAMS.items()}
    states = []
    for q, qd, qdd in STATES:
        values = dict(param_values)
        values.update({
            Q1: sp.Float(q[0], 30), Q2: sp.Float(q[1], 30),
            W1: sp.Float(qd[0], 30), W2: sp.Float(qd[1], 30),
            A1: sp.Float(qdd[0], 30), A2: sp.Float(qdd[1], 30),
        })
        entry = {"q": list(q), "qd": list(qd), "qdd": list(qdd)}
        for name, e in exprs.items():
            entry[name] = to_list(e, values)
        states.append(entry)
    params = {k: float(exact(v)) for k, v in PARAMS.items()}
    fixture = {
        "generator": "tools/golden/arm/make_golden.py (sympy " + sp.__version__ + ")",
        "conventions": "x right, z up, gravity -z; theta1 from +x to +z; theta2 relative; "
                       "matrices row-major [[r0c0, r0c1], [r1c0, r1c1]]; tau = M qdd + C qd + g + B qd",
        "params": params,
        "states": states,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(fixture, indent=1) + "\n")
    print(f"wrote {OUT.relative_to(ROOT)}: {len(states)} states")


if __name__ == "__main__":
    main()
