"""Play an exported planar joint command on an arm simulated here, not by
limpid's lab (issue 60's outside check of a planar design): the robot moves
the arm rigidly along the command; the torque is the arm's inverse dynamics
(its own mass matrix and Coriolis terms, central-difference derivatives of
the command), the intrinsic K and D of seed 003's arm, optionally a stretch
reflex (delayed velocity and stretch feedback, not limpid's gain step),
AR(1) torque fluctuation (0.15 N m, 0.3 s), a constant offset per trial,
0.05 N m white noise, 0.005 N m quantisation and 2e-5 rad angle noise.

    limpid protocol export designed.toml -o command.csv
    python3 scripts/play-planar-command.py command.csv SEED REST_S recording.csv [reflex]
    limpid estimate planar recording.csv --link-lengths 0.3,0.33

REST_S: the recorded rest before each onset (the protocol's rest_s). With
`reflex`: 60 ms after the stretch, a torque of 0.3 K Δq + 0.3 D q' of that
moment. Needs numpy. Writes t, q1, q2, tau1, tau2, trial (each trial's rest
and window)."""
import sys

import numpy as np

cmd = np.genfromtxt(sys.argv[1], delimiter=",", names=True)
seed = int(sys.argv[2]); rest = float(sys.argv[3]); out = sys.argv[4]
reflex = len(sys.argv) > 5 and sys.argv[5] == "reflex"
xi = np.array([0.356, 0.143, 0.147])
K = np.array([[37.95, 9.31], [9.31, 10.14]])
D = np.array([[1.854, 0.590], [0.590, 1.435]])
tau0 = np.array([0.37, 0.41])
rng = np.random.default_rng(seed)
t = cmd["t"]; dt = t[1] - t[0]; n = len(t)
q = np.stack([cmd["q1"], cmd["q2"]], 1)
q0 = q[0].copy()
qd = np.gradient(q, dt, axis=0); qdd = np.gradient(qd, dt, axis=0)
c2, s2 = np.cos(q[:, 1]), np.sin(q[:, 1])
# M(q) q'' + C(q, q') q' for a 2-link arm in base parameters ξ
m11 = xi[0] + 2 * xi[1] * c2; m12 = xi[2] + xi[1] * c2; m22 = xi[2]
inertial = np.stack([m11 * qdd[:, 0] + m12 * qdd[:, 1] - xi[1] * s2 * (2 * qd[:, 0] * qd[:, 1] + qd[:, 1] ** 2),
                     m12 * qdd[:, 0] + m22 * qdd[:, 1] + xi[1] * s2 * qd[:, 0] ** 2], 1)
tau = inertial + (q - q0) @ K.T + qd @ D.T + tau0
if reflex:
    lag = int(round(0.06 / dt))
    late = np.zeros_like(q); late_v = np.zeros_like(q)
    late[lag:] = (q - q0)[:-lag]; late_v[lag:] = qd[:-lag]
    tau += 0.3 * (late @ K.T + late_v @ D.T)
phi = np.exp(-dt / 0.3); s = np.zeros(2); fluct = np.zeros((n, 2))
for i in range(n):
    s = phi * s + np.sqrt(1 - phi**2) * rng.standard_normal(2)
    fluct[i] = s
tau += 0.15 * fluct + 0.05 * rng.standard_normal((n, 2))
tau = np.round(tau / 0.005) * 0.005
angle = q + 2e-5 * rng.standard_normal((n, 2))
trial = cmd["trial"].astype(int)
onsets = [i for i in range(1, n) if trial[i] > 0 and trial[i - 1] == 0]
r = int(round(rest / dt))
with open(out, "w") as fh:
    fh.write("t,q1,q2,tau1,tau2,trial\n")
    row = 0  # the windows back to back at the sample rate, as a recorder keeps them
    for i0 in onsets:
        k = trial[i0]
        end = i0
        while end < n and trial[end] == k:
            end += 1
        offset = 0.1 * rng.standard_normal(2)
        for i in range(max(i0 - r, 0), end):
            fh.write("%.6f,%.9g,%.9g,%.6g,%.6g,%d\n" % (row * dt, *angle[i], *(tau[i] + offset), k))
            row += 1
