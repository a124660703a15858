#!/usr/bin/python3
"""The roots that test_stab_long_steps.pf's Kepler cases compare vci's long Lobatto steps with.

A Lobatto step of s stages from (q0, p0) solves, for the nodes Q_1 .. Q_s of the degree-s polynomial
through Q_0 = q0 at the Lobatto points (docs/SCHEMES.md),
    p0 = -dL_d/dQ_0,   0 = dL_d/dQ_j (j = 1 .. s-1),   p1 = dL_d/dQ_s,
    L_d = h sum_i b_i L(Q_i, V_i),   V_i = (1/h) sum_j D_ij Q_j,   L = |v|^2/2 + 1/|q|.
At a long h these equations have several roots. The one the motion follows is the one continued in h
from a short step (where the step is a small perturbation of the flow): this script starts at
h = 0.02 from the straight line q0 + c h p0 and follows the root in 2 % steps of h (Newton with the
analytic Jacobian at each), polishing at the target h to a residual near 1e-15. It is independent of
the library (numpy only) and prints q1 and the change of H for each case the tests name.

    /usr/bin/python3 tools/stability/continued_roots.py
"""
import numpy as np


def lobatto(s):
    """Lobatto nodes on [0, 1] (s + 1 of them), weights, and D_ij = l_j'(c_i)."""
    if s == 1:
        x = np.array([-1.0, 1.0])
    else:
        x = np.concatenate(([-1.0], np.sort(np.polynomial.legendre.Legendre.basis(s).deriv().roots()), [1.0]))
    pn = np.polynomial.legendre.Legendre.basis(s)(x)
    w = 2.0 / (s * (s + 1) * pn**2)
    c, b = (x + 1.0) / 2.0, w / 2.0
    d = np.zeros((s + 1, s + 1))
    for j in range(s + 1):
        others = np.delete(c, j)
        lj = np.poly1d(others, r=True) / np.prod(c[j] - others)
        d[:, j] = lj.deriv()(c)
    return c, b, d


def residual(nodes_rest, q0, p0, h, s, c, b, d):
    q = np.vstack([q0, nodes_rest.reshape(s, 2)])
    v = d @ q / h
    r = np.linalg.norm(q, axis=1)
    grad_u = -q / r[:, None] ** 3
    dld = h * b[:, None] * grad_u + d.T @ (b[:, None] * v)  # dL_d/dQ_j, j = 0 .. s
    res = [p0 + dld[0]] + [dld[j] for j in range(1, s)]
    return np.concatenate(res), dld[s]


def jacobian(nodes_rest, q0, p0, h, s, c, b, d):
    q = np.vstack([q0, nodes_rest.reshape(s, 2)])
    n = 2 * s
    jac = np.zeros((n, n))
    # d(dL_d/dQ_j)/dQ_k = h b_j Hess U(Q_j) delta_jk + (1/h) sum_i b_i D_ij D_ik
    m = d.T @ (b[:, None] * d) / h
    rows = [0] + list(range(1, s))
    for a, j in enumerate(rows):
        for k in range(1, s + 1):
            blk = m[j, k] * np.eye(2)
            if j == k:
                r = np.linalg.norm(q[j])
                blk = blk + h * b[j] * (-np.eye(2) / r**3 + 3.0 * np.outer(q[j], q[j]) / r**5)
            jac[2 * a:2 * a + 2, 2 * (k - 1):2 * k] = blk
    return jac


def continued_step(q0, p0, h_target, s):
    c, b, d = lobatto(s)
    h = 0.02
    x = np.concatenate([q0 + ck * h * p0 for ck in c[1:]])
    while True:
        for _ in range(50):
            f, _p1 = residual(x, q0, p0, h, s, c, b, d)
            dx = np.linalg.solve(jacobian(x, q0, p0, h, s, c, b, d), -f)
            x = x + dx
            if np.max(np.abs(dx)) < 1e-15 * max(1.0, np.max(np.abs(x))):
                break
        if h >= h_target:
            break
        h_next = min(h * 1.02, h_target)
        h = h_next  # the previous root is the next start: a 2 % longer step moves it little
    f, p1 = residual(x, q0, p0, h, s, c, b, d)
    return x.reshape(s, 2)[-1], p1, np.max(np.abs(f))


def energy(q, p):
    return 0.5 * p @ p - 1.0 / np.linalg.norm(q)


def main():
    q0, p0 = np.array([0.5, 0.0]), np.array([0.0, np.sqrt(3.0)])  # pericentre of a = 1, e = 0.5
    print("free Kepler from the pericentre, Lobatto s = 2 (test_kepler_free_lobatto2_start):")
    for h in (0.8, 1.0):
        q1, p1, res = continued_step(q0, p0, h, 2)
        print(f"  h = {h:.1f}: q1 = ({q1[0]:.15f}, {q1[1]:.15f}), residual {res:.1e}")
    starts = {3: [4.85352381380772413e-01, -3.80747878103467885e-02, -7.97230812772902420e-01, -1.56318320976782599e+00],
              2: [-5.71324935845350268e-01, 2.27997807610312964e-01, 5.00221107107056695e-01, -1.71544187560289396e+00]}
    print("close pericentre passages at h = 0.6 (test_kepler_close_pericentre_steps):")
    for s, st in starts.items():
        qs, ps = np.array(st[:2]), np.array(st[2:])
        q1, p1, res = continued_step(qs, ps, 0.6, s)
        print(f"  s = {s}: q1 = ({q1[0]:.15f}, {q1[1]:.15f}), H - H0 = {energy(q1, p1) - energy(qs, ps):.16f}, "
              f"residual {res:.1e}")
    # below the wall, s = 2, h = 0.8: step 10 (vci_long_steps_trace 4 2 0.8 16 1), no impact in it
    st = [2.08966092948540738e-01, -3.30385964245238306e-01, -1.77861532818925294e+00, -9.95332119977030860e-01]
    qs, ps = np.array(st[:2]), np.array(st[2:])
    q1, p1, res = continued_step(qs, ps, 0.8, 2)
    print(f"close pericentre passage at h = 0.8, s = 2: q1 = ({q1[0]:.15f}, {q1[1]:.15f}), "
          f"H - H0 = {energy(q1, p1) - energy(qs, ps):.16f}, residual {res:.1e}")
    # below the wall, s = 2, h = 0.6: step 12's impact (vci_long_steps_trace 4 2 0.6 1 1 before the
    # blended root was refused): the leaving sub-step of (1 - alpha) h from the wall with the blended
    # root's p+ is the continued root too; what went wrong is the impulse, not the sub-step's branch
    qt, pp = np.array([5.90487595910294538e-01, 1.0e-1]), np.array([-4.83983089690613211e-01, -8.46399921239833652e-01])
    q1, p1, res = continued_step(qt, pp, (1.0 - 1.96320195628199884e-01) * 0.6, 2)
    print(f"blended impact at h = 0.6, s = 2, leaving sub-step: q1 = ({q1[0]:.15f}, {q1[1]:.15f}), "
          f"H(q1, p1) - H(q~, p+) = {energy(q1, p1) - energy(qt, pp):.4f}, residual {res:.1e}")


if __name__ == "__main__":
    main()
