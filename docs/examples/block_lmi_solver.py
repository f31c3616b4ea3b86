"""The general solver on its own: the smallest-trace Lyapunov matrix of a stable discrete system.

Minimise trace(P) subject to A'PA - P + I <= 0 and P >= I. Every feasible P lies above the
solution of the Lyapunov equation A'PA - P + I = 0, which is itself >= I, so the optimum is that
solution: scipy's solve_discrete_lyapunov is the outside reference.
"""

import numpy as np
from scipy.linalg import solve_discrete_lyapunov

from lmi import BlockLMISolver

a = np.array([[0.9, 0.2, 0.0], [-0.1, 0.8, 0.3], [0.0, -0.2, 0.7]])
n = a.shape[0]

# the variables: the entries P[r, s], r <= s; E is the symmetric basis matrix of each
pairs = [(r, s) for r in range(n) for s in range(r, n)]
basis = np.zeros((len(pairs), n, n))
for i, (r, s) in enumerate(pairs):
    basis[i, r, s] = basis[i, s, r] = 1.0
c = np.array([1.0 if r == s else 0.0 for r, s in pairs])  # trace(P)

# C_j - sum_i x_i A_ij >= 0 for each block:
# -I - (A'PA - P) >= 0  and  P - I >= 0
lyapunov = (-np.eye(n), np.array([a.T @ e @ a - e for e in basis]))
above_identity = (-np.eye(n), -basis)

res = BlockLMISolver(c, [lyapunov, above_identity]).solve()
p = np.zeros((n, n))
for (r, s), value in zip(pairs, res.x, strict=True):
    p[r, s] = p[s, r] = value
reference = solve_discrete_lyapunov(a.T, np.eye(n))

print("status:", res.status, "| iterations:", res.iterations)
print(f"trace(P): {np.trace(p):.6f} | scipy: {np.trace(reference):.6f}")
print("P equals scipy's to 1e-7:", bool(np.max(np.abs(p - reference)) <= 1e-7 * np.max(np.abs(reference))))
