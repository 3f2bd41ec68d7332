"""Play an exported periodic end-point command on a subject simulated here,
not by limpid's lab (issue 60's outside check of a stochastic design):
a first-order 25 Hz servo, central-difference derivatives, AR(1)
signal-dependent force noise (20 %, 0.3 s), random-walk drift, a 2 N offset,
0.15 N white noise, 0.01 N quantisation; seed 000 Table I subject 1 at S1.

    limpid protocol export designed.toml -o command.csv
    python3 scripts/play-endpoint-command.py command.csv SEED recording.csv
    limpid estimate stochastic recording.csv --period P --band LO,HI

Needs numpy. Writes t, x, y, z, fx, fy, fz, period."""
import sys

import numpy as np

cmd = np.genfromtxt(sys.argv[1], delimiter=",", names=True)
seed = int(sys.argv[2]); out = sys.argv[3]
M = np.array([[0.4, 0.03, 0.02], [0.03, 0.35, 0.01], [0.02, 0.01, 0.19]])
B = np.array([[80.0, 22.0, 25.0], [22.0, 50.0, 47.0], [25.0, 47.0, 86.0]])
K = np.array([[1002.0, 12.0, 26.0], [12.0, 250.0, 94.0], [26.0, 94.0, 320.0]])
rng = np.random.default_rng(seed)
t = cmd["t"]; dt = t[1] - t[0]; n = len(t)
c = np.stack([cmd["x"], cmd["y"], cmd["z"]], 1)
x = np.zeros_like(c); a = dt / (1 / (2 * np.pi * 25) + dt)
for i in range(1, n):
    x[i] = x[i - 1] + a * (c[i] - x[i - 1])
v = np.gradient(x, dt, axis=0); acc = np.gradient(v, dt, axis=0)
own = x @ K.T + v @ B.T
phi = np.exp(-dt / 0.3); f = np.zeros((n, 3)); s = np.zeros(3)
for i in range(n):
    s = phi * s + np.sqrt(1 - phi**2) * rng.standard_normal(3)
    f[i] = s
drift = np.cumsum(rng.standard_normal((n, 3)) * 0.002, 0)
force = acc @ M.T + own + 0.2 * f * np.abs(own) + 2 * rng.standard_normal(3) + drift + 0.15 * rng.standard_normal((n, 3))
force = np.round(force / 0.01) * 0.01
pos = x + 2e-5 * rng.standard_normal((n, 3)) + np.array([0.6, 0, 0])
with open(out, "w") as fh:
    fh.write("t,x,y,z,fx,fy,fz,period\n")
    for i in range(n):
        fh.write("%g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%d\n" % (t[i], *pos[i], *force[i], cmd["period"][i]))
