"""Adaptive fuzzy approximators of the FBSM (paper (27)–(30), docs/model.md §4.1, §4.5).

f̂(v) = θ_fᵀξ(v) and b̂(v) = θ_bᵀξ(v) use 5 Gaussian membership functions on each of the five
inputs v = (u, v, w, q, r): 5⁵ = 3125 rules, product inference and centre-average
defuzzification. Because the Gaussians factorise, the normalised basis is the Kronecker product
of the five per-input normalised 5-vectors (never a loop over rules); subtracting each input's
largest exponent makes it safe against underflow. The compiled loop keeps ξ factorised as
(μ_1 ⊗ μ_2) ⊗ (μ_3 ⊗ μ_4 ⊗ μ_5) and never writes its 3125 entries: the dot products and the
updates stream θ once each, which made it 2.6× faster than materialising ξ.
d̂(S) = θ_dᵀξ_d(S) uses three Gaussians in the sliding variable S.

Adaptive laws (30), Euler-integrated at the control period dt, with optional σ-modification
leakage σ_l (docs/model.md §4.8) and projection of every θ_b entry into [0.5, 2]·b_n:

    θ̇_f = α_f (S ξ − σ_l θ_f),   θ̇_b = α_b (S ξ τ − σ_l (θ_b − b_n)),   θ̇_d = α_d (S ξ_d − σ_l θ_d)

Adaptation is frozen while the loop's command saturates (anti-windup).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from controllers.gains import ALPHA_B, ALPHA_D, ALPHA_F, DT, MF1, SEPARATE_B, SIGMA_LEAK

__all__ = ["N_RULES", "WORK_DIM", "adaptive_loop", "basis_factors", "fuzzy_basis", "memberships"]

N_INPUTS = 5
N_SETS = 5
N_RULES = N_SETS**N_INPUTS  # 3125


@njit(cache=True, inline="always")
def memberships(x, centre0, spacing, width, out):
    """Normalised memberships of x in 5 Gaussians exp(−((x − c_j)/σ)²), c_j = c_0 + j·Δc."""
    largest = -np.inf
    for j in range(N_SETS):
        d = (x - (centre0 + j * spacing)) / width
        out[j] = -d * d
        largest = max(largest, out[j])
    total = 0.0
    for j in range(N_SETS):
        out[j] = math.exp(out[j] - largest)
        total += out[j]
    for j in range(N_SETS):
        out[j] /= total


@njit(cache=True, inline="always")
def basis_factors(mu, ab, cde):
    """The two factors of ξ = ab ⊗ cde: ab = μ_1 ⊗ μ_2 (25), cde = μ_3 ⊗ μ_4 ⊗ μ_5 (125).

    Rule l = (j1, …, j5) has index 5⁴j1 + 5³j2 + 5²j3 + 5j4 + j5 = 125·(5j1 + j2) + (25j3 + 5j4
    + j5), so ξ_l = ab[5j1 + j2]·cde[25j3 + 5j4 + j5] — the order of `fuzzy_basis` and np.kron.
    """
    for a in range(N_SETS):
        for b in range(N_SETS):
            ab[a * N_SETS + b] = mu[0, a] * mu[1, b]
    for c in range(N_SETS):
        for d in range(N_SETS):
            cd = mu[2, c] * mu[3, d]
            for e in range(N_SETS):
                cde[(c * N_SETS + d) * N_SETS + e] = cd * mu[4, e]


def fuzzy_basis(v: np.ndarray, p: float, q_mf: float, sigma: float) -> np.ndarray:
    """Numpy reference of the normalised 3125-rule basis for a batch v (n, 5) → (n, 3125).

    Centres −p + j·q_mf, j = 0..4; computed as an outer-product chain over the inputs.
    """
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    centres = -p + q_mf * np.arange(N_SETS)
    expo = -(((v[:, :, None] - centres) / sigma) ** 2)
    mu = np.exp(expo - expo.max(axis=2, keepdims=True))
    mu /= mu.sum(axis=2, keepdims=True)
    basis = mu[:, 0]
    for i in range(1, N_INPUTS):
        basis = (basis[:, :, None] * mu[:, i, None, :]).reshape(v.shape[0], -1)
    return basis


@njit(cache=True, inline="always")
def _dot(a, b):
    """Σ a_i b_i with four interleaved partial sums: a fixed summation order (bit-reproducible)
    that the compiler can still map onto SIMD lanes."""
    s0 = s1 = s2 = s3 = 0.0
    n4 = a.shape[0] - a.shape[0] % 4
    for i in range(0, n4, 4):
        s0 += a[i] * b[i]
        s1 += a[i + 1] * b[i + 1]
        s2 += a[i + 2] * b[i + 2]
        s3 += a[i + 3] * b[i + 3]
    for i in range(n4, a.shape[0]):
        s0 += a[i] * b[i]
    return (s0 + s1) + (s2 + s3)


# Scratch layout of one loop evaluation (`WORK_DIM` floats): μ (5×5), then per basis (f̂, b̂)
# the factors ab (25) and cde (125) and the partial sums acc (125).
_N_AB, _N_CDE = N_SETS**2, N_SETS**3
_AB = N_SETS * N_SETS  # μ occupies work[:_AB]
_CDE = _AB + 2 * _N_AB
_ACC = _CDE + 2 * _N_CDE
WORK_DIM = _ACC + 2 * _N_CDE


@njit(cache=True)
def adaptive_loop(loop, v_in, S, rest, limit, b_nominal, theta_f, theta_b, theta_d, g, work, diag):
    """One FBSM loop (29)–(30): τ = (−f̂ − d̂(S) + rest)/b̂, saturated; adapts; returns τ/limit.

    ``rest`` is the model-free part of the law (e.g. −c1ż1 + α̇1 − (h + λ)S for pitch),
    ``limit`` the actuator limit of this input (≤ 0 means no authority: full saturation),
    ``work`` a scratch vector of `WORK_DIM` floats. ``diag`` receives (f̂, b̂, d̂).

    ξ = ab ⊗ cde is never materialised: with θ viewed as a 25 × 125 matrix,
    f̂ = Σ_j cde_j Σ_i ab_i θ_ij (25 vectorised row passes, then one 125-term sum), and the
    update θ_ij += (step·ab_i)·cde_j streams each row once. Every sum has a fixed order, so a
    vehicle's result does not depend on the batch it is computed in.
    """
    base = MF1 + 5 * loop
    centre0, spacing, sigma = g[base], g[base + 1], g[base + 2]
    sigma_b, sigma_d = g[base + 3], g[base + 4]
    mu = work[:_AB].reshape((N_SETS, N_SETS))
    ab, ab_b = work[_AB : _AB + _N_AB], work[_AB + _N_AB : _CDE]
    cde, cde_b = work[_CDE : _CDE + _N_CDE], work[_CDE + _N_CDE : _ACC]
    acc_f, acc_b = work[_ACC : _ACC + _N_CDE], work[_ACC + _N_CDE : WORK_DIM]
    for i in range(N_INPUTS):
        memberships(v_in[i], centre0, spacing, sigma, mu[i])
    basis_factors(mu, ab, cde)
    if g[SEPARATE_B] > 0.0:
        for i in range(N_INPUTS):
            memberships(v_in[i], centre0, spacing, sigma_b, mu[i])
        basis_factors(mu, ab_b, cde_b)
    else:  # b̂ shares f̂'s basis (σ_b = σ, docs/model.md §4.6)
        ab_b, cde_b = ab, cde
    acc_f[:] = 0.0
    acc_b[:] = 0.0
    for i in range(_N_AB):
        w_f, w_b, row = ab[i], ab_b[i], i * _N_CDE
        for j in range(_N_CDE):
            acc_f[j] += w_f * theta_f[row + j]
            acc_b[j] += w_b * theta_b[row + j]
    f_hat = _dot(cde, acc_f)
    b_hat = _dot(cde_b, acc_b)
    e0 = -(((S + sigma_d) / sigma_d) ** 2)
    e1 = -((S / sigma_d) ** 2)
    e2 = -(((S - sigma_d) / sigma_d) ** 2)
    top = max(e0, max(e1, e2))
    e0, e1, e2 = math.exp(e0 - top), math.exp(e1 - top), math.exp(e2 - top)
    total = e0 + e1 + e2
    e0, e1, e2 = e0 / total, e1 / total, e2 / total
    d_hat = theta_d[0] * e0 + theta_d[1] * e1 + theta_d[2] * e2
    tau = (-f_hat - d_hat + rest) / b_hat
    if limit > 0.0:
        action = tau / limit
    else:
        action = math.copysign(np.inf, tau) if tau != 0.0 else 0.0
    saturated = abs(action) > 1.0
    action = min(max(action, -1.0), 1.0)
    if not saturated:
        dt, leak = g[DT], g[SIGMA_LEAK]
        tau_applied = action * limit if limit > 0.0 else 0.0
        step_f = dt * g[ALPHA_F] * S
        step_b = dt * g[ALPHA_B] * S * tau_applied
        gain_d = dt * g[ALPHA_D]
        low, high = 0.5 * b_nominal, 2.0 * b_nominal
        leak_f, leak_b = dt * g[ALPHA_F] * leak, dt * g[ALPHA_B] * leak
        for i in range(_N_AB):
            s_f, s_b, row = step_f * ab[i], step_b * ab_b[i], i * _N_CDE
            if leak == 0.0:  # the paper's laws; simple loops that the compiler vectorises
                for j in range(_N_CDE):
                    theta_f[row + j] += s_f * cde[j]
                for j in range(_N_CDE):  # projection into [0.5, 2]·b_n
                    theta_b[row + j] = min(max(theta_b[row + j] + s_b * cde_b[j], low), high)
            else:
                for j in range(_N_CDE):
                    k = row + j
                    theta_f[k] += s_f * cde[j] - leak_f * theta_f[k]
                    updated = theta_b[k] + s_b * cde_b[j] - leak_b * (theta_b[k] - b_nominal)
                    theta_b[k] = min(max(updated, low), high)
        theta_d[0] += gain_d * (S * e0 - leak * theta_d[0])
        theta_d[1] += gain_d * (S * e1 - leak * theta_d[1])
        theta_d[2] += gain_d * (S * e2 - leak * theta_d[2])
    diag[0], diag[1], diag[2] = f_hat, b_hat, d_hat
    return action
