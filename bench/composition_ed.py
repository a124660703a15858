#!/usr/bin/python3
"""E_d - H of one composed step of length tau from a fixed state of the walled pendulum's
potential (V = -9.8 cos q, M = 1; q = 1, p = 3), for Verlet and the composition orders 4 and 6
(the triple jump; the order-6 triple jump of the order-4 one). E_d is the composed discrete
Lagrangian's energy, sum_i gamma_i [1/2 pbar_i^2 + (V(q_(i-1)) + V(q_i))/2] (docs/SCHEMES.md,
"The discrete condition for the compositions"). Shows that E_d - H = O(tau^p) and its size.

    /usr/bin/python3 bench/composition_ed.py
"""
import math

G = 9.8


def V(q):
    return -G * math.cos(q)


def dV(q):
    return G * math.sin(q)


def triple(g, p):
    """The triple jump raising the symmetric composition g of order p to order p + 2."""
    a = 1.0 / (2.0 - 2.0 ** (1.0 / (p + 1)))
    b = 1.0 - 2.0 * a
    return [a * x for x in g] + [b * x for x in g] + [a * x for x in g]


def energy(q, p, tau, gammas):
    e, vp = 0.0, V(q)
    for gi in gammas:
        pb = p - 0.5 * gi * tau * dV(q)
        q1 = q + gi * tau * pb
        p = pb - 0.5 * gi * tau * dV(q1)
        e += gi * (0.5 * pb * pb + 0.5 * (vp + V(q1)))
        vp, q = V(q1), q1
    return e


def main():
    q, p = 1.0, 3.0
    h0 = 0.5 * p * p + V(q)
    sets = (("verlet (order 2)", 2, [1.0]), ("triple jump (order 4)", 4, triple([1.0], 2)),
            ("triple jump of it (order 6)", 6, triple(triple([1.0], 2), 4)))
    for name, order, gammas in sets:
        print(name)
        prev = None
        for tau in (0.2, 0.1, 0.05, 0.025, 0.0125):
            d = energy(q, p, tau, gammas) - h0
            rate = "" if prev is None else f"  observed order {math.log2(abs(prev / d)):5.2f}"
            print(f"  tau {tau:7.4f}  E_d - H {d: .3e}{rate}")
            prev = d


if __name__ == "__main__":
    main()
