r"""Guidance against ocean currents: a current observer, crab angles over ground, gated ALOS.

Not in the paper; composes with its LOS (`controllers.los`) for FBSM and backstepping. Every
quantity comes from the observation (`auv_gym.OBS_NAMES`): ε = (x_e, y_e, z_e), ψ_e = ψ − ψ_F,
θ, θ_F, the velocities through the water ν = (u, v, w), the rates q, r, u_D and u_p — what a
real AUV has from its navigation (position, attitude) and its velocity sensors. No velocity over
ground and no knowledge of the current is used. Notation as docs/model.md §3.2–§3.4.

1. Current observer (``current_observer`` = ω_o > 0). With a current v_c that is constant in
   the earth frame, the error kinematics of docs/model.md §3.2 read

       ε̇ = −ω_b × ε + ν + c − t u_p,    ċ = −ω_b × c,    c = R_Bᵀ v_c,  t = R_Bᵀ R_F e1,

   with ω_b = (−r tanθ, q, r) (roll held at zero) and t the path tangent in body axes, computed
   from ψ_e, θ, θ_F. The observer copies them with output injection, ε̃ = ε − ε̂:

       ε̂̇ = −ω_b × ε + ν + ĉ − t u_p + 2ω_o ε̃,    ĉ̇ = −ω_b × ĉ + ω_o² ε̃

   (the rotation term uses the measured ε). The error (ε̃, c̃ = c − ĉ) obeys ε̃̇ = c̃ − 2ω_o ε̃,
   c̃̇ = −ω_b × c̃ − ω_o² ε̃ (+ v̇_c for a varying current); V = ω_o²|ε̃|² + |c̃|² gives
   V̇ = −4ω_o³|ε̃|² because c̃·(ω_b × c̃) = 0, and without rotation the system is linear with a
   double pole at −ω_o. It is globally exponentially stable for any motion of the vehicle
   with bounded rates and any path (the kinematic observer of
   Aguiar & Pascoal 2007, used for curved-path following by Moe, Caharija, Pettersen &
   Schjølberg 2014 and Maghenem, Belleter, Paliotta & Pettersen 2017, here written in body axes
   so that it needs no earth-frame position). A slowly varying current is tracked with the lag
   of that second-order filter; it estimates the current, so it has nothing to wind up.
   The presets use ω_o = 3 rad/s (discretised at the control period, `observe_current`). The
   simulator's navigation is noise-free; real position noise calls for a lower ω_o, at the cost
   of a lag behind a varying current that grows as 1/ω_o (FBSM on the `current` scenario,
   seeds 0–3: 0.090 m at ω_o = 1, 0.077 m at 2, 0.066 m at 3 rad/s).

2. Crab angles over ground (Fossen & Aguiar 2024; Coates & Fossen 2025). With the estimated
   velocity over ground ν_g = ν + ĉ = (u_g, v_g, w_g) in body axes, the horizontal crab angle
   (course minus heading) and the flight-path angle are

       β_c = atan2(v_g, u_g cosθ + w_g sinθ),
       γ = atan2(u_g sinθ − w_g cosθ, √((u_g cosθ + w_g sinθ)² + v_g²)),   α_c = θ − γ,

   α_c being the vertical crab angle of Coates & Fossen's spherical form. In still water and
   with v = 0 they reduce to the paper's α = arctan(w/u); β_c is the paper's β with the 3-D
   correction of docs/model.md §10 item 5. The LOS laws become course and flight-path commands:

       ψ_d = ψ_F − arctan(k_y y_e) − β_c − β̂,    θ_d = sat(θ_F + arctan(k_z z_e) + α_c + α̂, ±θ_max),

   so that, with the attitude loops converged, ẏ_e ≈ −U_h sin(arctan(k_y y_e) + β̃) and
   ż_e ≈ −U sin(arctan(k_z z_e) + α̃) near the path (x_e → 0), with β̃, α̃ the residual crab-angle
   errors. The lookahead distances are Δ_h = 1/k_y, Δ_v = 1/k_z. On a straight line with a
   constant current the observer error is a GES perturbation entering this (USGES, Fossen &
   Aguiar 2024) LOS system, so the cascade is USGES: y_e, z_e → 0.

   The corrections pass the command filter of docs/model.md §10 item 4. A 2nd-order filter lags
   a ramp by 2ζ/ω_n = 1 s, and on the helix the crab angle turns by ±17° per 132-s turn: that
   lag alone left 0.1 m of cross-track error. So the filter is fed the rate of the corrections
   that the turning estimate ĉ (at fixed ν, θ) and the trims cause, ċ_ff, as
   ẍ = ω_n²(c − x) + 2ζω_n(ċ_ff − ẋ), which follows a ramp without lag (0.10 → 0.026 m,
   backstepping, constant 0.3 m/s current). The paper's filter (ċ_ff absent) is unchanged.

3. Adaptive LOS trims (``alos_y`` = γ_h, ``alos_z`` = γ_v; Fossen & Aguiar 2024, Automatica
   163:111556, eq. of MSS `ALOS3D.m`), with a capture gate g and projection onto [−M, M]:

       β̂̇ = γ_h g(|ε|) Δ_h y_e / √(Δ_h² + y_e²),    α̂̇ = γ_v g(|ε|) Δ_v z_e / √(Δ_v² + z_e²),
       g(d) = 1 / (1 + (d/R)⁴),   R = ``alos_radius``,   M = ``alos_max``.

   They absorb whatever the observer leaves: its lag behind a varying current, and the
   difference between the body-frame errors and the path-frame geometry on a curved path.
   Stability conditions relied on: Fossen & Aguiar prove USGES of (y_e, z_e, β̃, α̃) for a
   straight line, constant crab angles, U > 0 and perfect attitude tracking (a cascade with
   the FBSM/backstepping loops, which converge exponentially on S = 0); Coates & Fossen extend
   it to a class of curved paths. The gate keeps the adaptation off during the approach: g ≤
   1/17 beyond 2R and g ≈ 10⁻⁵ at the paper's start (|ε| = 17.7 m, R = 1 m), so the trims
   integrate at most γ Δ g per second there instead of γ Δ. Outside the gate
   β̂, α̂ are (nearly) constant and bounded by M, and the plain LOS with a constant crab-angle
   error β̃ is input-to-state stable: it brings y_e to within Δ_h tan|β̃| of the path. The
   observer makes β̃ small (it does not depend on the tracking error), so the vehicle enters
   the gate, where the ALOS result applies. Without the observer (pure ALOS) β̃ is the whole
   crab angle, ≈ 17° for 0.3 m/s at 1 m/s, and R must exceed Δ_h tan 17° ≈ 3 m — the approach
   is then partly inside the gate; that is why the observer carries the current and ALOS only
   trims. Measured (FBSM, 2 seeds, pure ALOS γ = 0.1, R = 4 m): 0.19 m on the helix in the
   0.3 m/s current (the crab angle it must learn rotates with the path, which a constant-
   parameter law can only chase), 0.11 m instead of 0.064 m under the paper's white noise,
   settling 52 s instead of 31 s. The trims do earn their place on top of the observer where
   the inner loop leaves a bias: backstepping with a ±30 % model error, 0.081 → 0.005 m.

4. Speed over ground (``speed_over_ground``). The virtual point moves at u_p = u_D(1 +
   tanh(x_e/σ)), so it waits at x_e = 0 only if the vehicle makes u_D over ground along the
   path; with a current c along the path and surge u_D through the water it lags by
   x_e = σ artanh(c/u_D) (0.16 m for 0.3 m/s). The surge reference becomes the speed through
   the water that gives u_D over ground along t, and its rate is fed forward:

       u_ref = √((u_D − t·ĉ)² + |ĉ|² − (t·ĉ)²),   u̇_ref by finite difference over one step,

   limited to [u_D/2, 2u_D]. In still water ĉ = 0 and u_ref = u_D exactly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "ALPHA_HAT",
    "BETA_HAT",
    "C_HAT",
    "EPS_HAT",
    "G_PREV",
    "U_REF",
    "adapt_trims",
    "crab_angles",
    "guidance_diagnostics",
    "observe_current",
    "path_tangent",
    "speed_reference",
]

# Offsets in the guidance memory (`controllers.los.FILTER_DIM`): ε̂ [m], ĉ [m/s], the last
# measured part g of ε̇ [m/s] (3 each), β̂, α̂ [rad], u_ref [m/s].
EPS_HAT, C_HAT, G_PREV, BETA_HAT, ALPHA_HAT, U_REF = 8, 11, 14, 17, 18, 19


@njit(cache=True, inline="always")
def path_tangent(psi_error, theta, theta_f):
    """t = R_Bᵀ R_F e1, the path's unit tangent in body axes, from ψ − ψ_F, θ, θ_F [rad]."""
    a = math.cos(psi_error) * math.cos(theta_f)
    b = -math.sin(psi_error) * math.cos(theta_f)
    dz = -math.sin(theta_f)
    cth, sth = math.cos(theta), math.sin(theta)
    return cth * a - sth * dz, b, sth * a + cth * dz


@njit(cache=True, inline="always")
def observe_current(x_e, y_e, z_e, u, v, w, q, r, theta, t0, t1, t2, u_p, wn, dt, started, filt):
    """One step of the current observer (module doc, 1) on its memory in ``filt``.

    The measured part of ε̇, g = −ω_b × ε + ν − t u_p, is integrated by the trapezoidal rule
    between the last and this sample (Euler would bias ĉ by ½dt·ġ while the vehicle turns in
    towards the path), then the innovation e = ε − ε̂⁻ corrects ε̂ and ĉ.
    """
    tth = math.tan(theta)
    # −ω_b × a = (r a_y − q a_z, −r a_x − r tanθ a_z, q a_x + r tanθ a_y), ω_b = (−r tanθ, q, r)
    gx = r * y_e - q * z_e + u - t0 * u_p
    gy = -r * x_e - r * tth * z_e + v - t1 * u_p
    gz = q * x_e + r * tth * y_e + w - t2 * u_p
    if not started:  # ε̂(0) = ε, ĉ(0) = 0
        filt[EPS_HAT], filt[EPS_HAT + 1], filt[EPS_HAT + 2] = x_e, y_e, z_e
        filt[C_HAT], filt[C_HAT + 1], filt[C_HAT + 2] = 0.0, 0.0, 0.0
        filt[G_PREV], filt[G_PREV + 1], filt[G_PREV + 2] = gx, gy, gz
        return
    cx, cy, cz = filt[C_HAT], filt[C_HAT + 1], filt[C_HAT + 2]
    ex = x_e - (filt[EPS_HAT] + dt * (0.5 * (filt[G_PREV] + gx) + cx))
    ey = y_e - (filt[EPS_HAT + 1] + dt * (0.5 * (filt[G_PREV + 1] + gy) + cy))
    ez = z_e - (filt[EPS_HAT + 2] + dt * (0.5 * (filt[G_PREV + 2] + gz) + cz))
    k1, k2 = 2.0 * wn, wn * wn
    filt[EPS_HAT] = x_e - (1.0 - dt * k1) * ex
    filt[EPS_HAT + 1] = y_e - (1.0 - dt * k1) * ey
    filt[EPS_HAT + 2] = z_e - (1.0 - dt * k1) * ez
    filt[C_HAT] = cx + dt * (r * cy - q * cz + k2 * ex)
    filt[C_HAT + 1] = cy + dt * (-r * cx - r * tth * cz + k2 * ey)
    filt[C_HAT + 2] = cz + dt * (q * cx + r * tth * cy + k2 * ez)
    filt[G_PREV], filt[G_PREV + 1], filt[G_PREV + 2] = gx, gy, gz


@njit(cache=True, inline="always")
def crab_angles(u_g, v_g, w_g, theta):
    """(β_c, α_c) [rad] of the velocity over ground (u_g, v_g, w_g) [m/s] (module doc, 2)."""
    cth, sth = math.cos(theta), math.sin(theta)
    forward = u_g * cth + w_g * sth
    gamma = math.atan2(u_g * sth - w_g * cth, math.sqrt(forward * forward + v_g * v_g))
    return math.atan2(v_g, forward), theta - gamma


@njit(cache=True, inline="always")
def adapt_trims(x_e, y_e, z_e, k_y, k_z, gamma_h, gamma_v, radius, bound, dt, filt):
    """One projected Euler step of the gated ALOS laws (module doc, 3) on β̂, α̂."""
    d2 = (x_e * x_e + y_e * y_e + z_e * z_e) / (radius * radius)
    gate = 1.0 / (1.0 + d2 * d2)
    beta = filt[BETA_HAT] + dt * gamma_h * gate * y_e / math.sqrt(1.0 + (k_y * y_e) ** 2)
    alpha = filt[ALPHA_HAT] + dt * gamma_v * gate * z_e / math.sqrt(1.0 + (k_z * z_e) ** 2)
    filt[BETA_HAT] = min(max(beta, -bound), bound)
    filt[ALPHA_HAT] = min(max(alpha, -bound), bound)


@njit(cache=True, inline="always")
def speed_reference(u_d, t0, t1, t2, cx, cy, cz):
    """u_ref [m/s]: speed through the water for u_D over ground along t (module doc, 4)."""
    along = t0 * cx + t1 * cy + t2 * cz
    across2 = max(cx * cx + cy * cy + cz * cz - along * along, 0.0)
    u_ref = math.sqrt((u_d - along) ** 2 + across2)
    return min(max(u_ref, 0.5 * u_d), 2.0 * u_d)


def guidance_diagnostics(gains, filt: np.ndarray) -> dict[str, np.ndarray]:
    """Extras for `auv_gym.rollout` from the guidance memory (n, FILTER_DIM), where switched
    on: ``current_hat`` (n, 3), the body-axis estimate ĉ [m/s]; ``beta_hat``, ``alpha_hat``
    (n,), the ALOS trims [rad]; ``u_ref`` (n,), the surge reference [m/s]."""
    out = {}
    if gains.current_observer > 0.0:
        out["current_hat"] = filt[:, C_HAT : C_HAT + 3].copy()
    if gains.alos_y > 0.0 or gains.alos_z > 0.0:
        out["beta_hat"] = filt[:, BETA_HAT].copy()
        out["alpha_hat"] = filt[:, ALPHA_HAT].copy()
    if gains.speed_over_ground:
        out["u_ref"] = filt[:, U_REF].copy()
    return out
