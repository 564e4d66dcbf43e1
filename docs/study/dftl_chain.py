#!/usr/bin/env python3
"""Why DFTL with shape crinkled a groom at 1 kHz: SB15's step linearised about a smooth
equilibrium, in 2-D (docs/design-departures.md, "the local correction's reaction is a bending
stencil").

A chain of 24 nodes, 0.25 m, curved 0.08 rad per segment, nodes 0 and 1 held, under gravity,
with the default shape fractions (s_g = 0.0066, s_l = 0.022 at 1 ms, rescaled as springs) and
s_d = 0.9: predict, global then local shape, follow the leader, then velocities with eq. 14's
reaction. `phi` hands (1 + phi) of the local correction's reaction to the node before and -phi
to the one before that (phi = 0 is SB15). The equilibrium is found by Newton's method on the
step map, the step's Jacobian by finite differences, and its spectral radius printed: above 1
the smooth groom is unstable.

    python3 docs/study/dftl_chain.py        # needs numpy; about 20 s
"""
import numpy as np

N, LENGTH, CURL, G, SD = 24, 0.25, 0.08, -9.81, 0.9
SG_REF, SL_REF, REF_DT = 0.0066, 0.022, 1e-3


def spring(s, dt):
    alpha = REF_DT * REF_DT * (1 - s) / s
    return dt * dt / (dt * dt + alpha)


def frame(t):
    return np.array([[t[0], -t[1]], [t[1], t[0]]])


def rest_chain():
    l = LENGTH / (N - 1)
    x, angle = np.zeros((N, 2)), 0.0
    for i in range(1, N):
        if i >= 2:
            angle += CURL
        x[i] = x[i - 1] + l * np.array([np.cos(angle), np.sin(angle)])
    r = np.zeros((N, 2))
    for i in range(2, N):
        t = (x[i - 1] - x[i - 2]) / np.linalg.norm(x[i - 1] - x[i - 2])
        r[i] = frame(t).T @ (x[i] - x[i - 1])
    return x, r, l


REST, LOCAL_REST, SEGMENT = rest_chain()


def step(x, v, dt, phi):
    sg, sl = spring(SG_REF, dt), spring(SL_REF, dt)
    xs = x + dt * v
    xs[:, 1] += dt * dt * G
    xs[:2] = REST[:2]
    local, inex = np.zeros((N, 2)), np.zeros((N, 2))
    for i in range(2, N):
        xs[i] += sg * (REST[i] - xs[i])
        t = (xs[i - 1] - xs[i - 2]) / np.linalg.norm(xs[i - 1] - xs[i - 2])
        local[i] = sl * (xs[i - 1] + frame(t) @ LOCAL_REST[i] - xs[i])
        xs[i] += local[i]
        e = xs[i] - xs[i - 1]
        projected = xs[i - 1] + e / np.linalg.norm(e) * SEGMENT
        inex[i], xs[i] = projected - xs[i], projected
    vn = (xs - x) / dt
    for i in range(2, N):
        reaction = np.zeros(2)
        if i + 1 < N:
            reaction += (1 + phi) * local[i + 1] + inex[i + 1]
        if i + 2 < N:
            reaction -= phi * local[i + 2]
        vn[i] -= SD * reaction / dt
    vn[:2] = 0
    return xs, vn


def flat(x, v):
    return np.concatenate([x[2:].ravel(), v[2:].ravel()])


def unflat(z):
    m = (N - 2) * 2
    x, v = REST.copy(), np.zeros_like(REST)
    x[2:], v[2:] = z[:m].reshape(-1, 2), z[m:].reshape(-1, 2)
    return x, v


def jacobian(f, z, h=1e-8):
    f0 = f(z)
    return np.column_stack([(f(z + h * e) - f0) / h for e in np.eye(len(z))])


def spectral_radius(dt, phi):
    f = lambda z: flat(*step(*unflat(z), dt, phi))
    z = flat(REST, np.zeros_like(REST))
    for _ in range(200):  # settle near the equilibrium, strongly damped
        x, v = step(*unflat(z), dt, phi)
        z = flat(x, 0.5 * v)
    for _ in range(6):  # Newton on f(z) = z
        z = z - np.linalg.solve(jacobian(f, z) - np.eye(len(z)), f(z) - z)
    return max(abs(np.linalg.eigvals(jacobian(f, z))))


if __name__ == "__main__":
    steps = (0.5e-3, 1e-3, 2e-3, 4e-3, 8e-3, 1 / 60)
    print("dt (ms)  s_l    SB15 (phi=0)  phi=1   phi=(1-s_l)/2")
    for dt in steps:
        sl = spring(SL_REF, dt)
        row = [spectral_radius(dt, phi) for phi in (0.0, 1.0, 0.5 * (1 - sl))]
        print(f"{dt * 1e3:6.1f}  {sl:.3f}  " + "  ".join(f"{r:.4f}" for r in row))
