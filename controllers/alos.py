r"""Guidance against ocean currents: a current observer, crab angles over ground, gated ALOS.

Not in the paper; an option of the paper's LOS (`controllers.los`) for FBSM, backstepping and
the PID, switched on by the gains ``current_observer``, ``alos_y``, ``alos_z``,
``speed_over_ground`` and ``dvl_current`` (presets ``fbsm_colos``, ``backstepping_colos``; manual:
docs/model.md §3.7). Every quantity comes from the observation (docs/model.md §11.2): the errors
ε = (x_e, y_e, z_e), ``psi_error`` ψ − ψ_F, θ, θ_F, the velocities through the water
ν = (u, v, w), the rates q, r, u_D and u_p — what a real AUV has from its navigation (position,
attitude), its velocity sensors and its own guidance. Without ``dvl_current`` no velocity over
ground and no knowledge of the current is used, so the paper's observation suffices; with it
(5) the current is read from the DVL's velocity over ground, an entry of the agents'
observation. Notation as docs/model.md §3.2 and §3.4.

1. Current observer (``current_observer`` = ω_o > 0). With a current v_c that is constant in
   the earth frame, the error kinematics of docs/model.md §3.2 read

       ε̇ = −ω_b × ε + ν + c − t u_p,    ċ = −ω_b × c,    c = R_Bᵀ v_c,  t = R_Bᵀ R_F e1,

   with ω_b = (−r tanθ, q, r) (roll held at zero) and t the path tangent in body axes, computed
   from ψ − ψ_F, θ, θ_F. The observer copies them with output injection, ε̃ = ε − ε̂:

       ε̂̇ = −ω_b × ε + ν + ĉ − t u_p + 2ω_o ε̃,    ĉ̇ = −ω_b × ĉ + ω_o² ε̃

   (the rotation term uses the measured ε). The error (ε̃, c̃ = c − ĉ) obeys ε̃̇ = c̃ − 2ω_o ε̃,
   c̃̇ = −ω_b × c̃ − ω_o² ε̃ (+ R_Bᵀ v̇_c for a varying current). V = ω_o²|ε̃|² + |c̃|² has
   V̇ = −4ω_o³|ε̃|², because c̃·(ω_b × c̃) = 0, and c̃ is uniformly observable from ε̃ (it enters
   ε̃̇ directly), so the error is uniformly globally exponentially stable; without rotation it
   is linear with a double pole at −ω_o. This holds for any motion with bounded rates and any
   path (the kinematic current observer of Aguiar & Pascoal 2007, used for curved-path
   following by Moe, Caharija, Pettersen & Schjølberg 2014 and Maghenem, Belleter, Paliotta &
   Pettersen 2017; written here in body axes so that it needs no earth-frame position).
   A slowly varying current is tracked with the lag of this second-order filter; it estimates
   the current, so there is nothing to wind up on the approach. Euler at the control period,
   with the measured part of ε̇ integrated by the trapezoidal rule
   (`observe_current`); without rotation its error has the characteristic polynomial
   λ² − (2 − 2h − h²)λ + 1 − 2h, h = ω_o Δt_c, stable for h < 2√2 − 2 ≈ 0.83 (checked when
   the gains are packed). The presets use ω_o = 3 rad/s. The simulator's
   navigation is noise-free; real position noise calls for a lower ω_o, at the cost of a lag
   behind a varying current that grows as 1/ω_o.

2. Crab angles over ground (Fossen & Aguiar 2024; Coates & Fossen 2025). With the estimated
   velocity over ground ν_g = ν + ĉ = (u_g, v_g, w_g) in body axes, the horizontal crab angle
   (course minus heading) and the flight-path angle are

       β_c = atan2(v_g, u_g cosθ + w_g sinθ),
       γ = atan2(u_g sinθ − w_g cosθ, √((u_g cosθ + w_g sinθ)² + v_g²)),   α_c = θ − γ,

   α_c being the vertical crab angle of Coates & Fossen's spherical amplitude–phase form (pitch
   minus flight-path angle of the velocity over ground). In still water and with v = 0 they
   reduce to the paper's α = arctan(w/u); β_c is the paper's β with the 3-D correction of
   docs/model.md §10.5. The LOS laws of docs/model.md §3.4 become course and flight-path
   commands:

       ψ_d = ψ_F − arctan(k_y y_e) − β_c − β̂,    θ_d = sat(θ_F + arctan(k_z z_e) + α_c + α̂, ±θ_max),

   so that, with the attitude loops converged, ẏ_e ≈ −U_h sin(arctan(k_y y_e) + β̃) and
   ż_e ≈ −U sin(arctan(k_z z_e) + α̃) near the path (x_e → 0), with β̃, α̃ the residual crab-angle
   errors and lookahead distances Δ_h = 1/k_y, Δ_v = 1/k_z. On a straight line with a constant
   current the observer error is a GES perturbation entering this LOS system, which is USGES
   (Fossen & Aguiar 2024, Theorem 1 with exact crab angles), so the cascade is USGES:
   y_e, z_e → 0 (`tests/test_current_guidance.py`).

   The corrections pass the command filter of docs/model.md §10.4. A 2nd-order filter lags a
   ramp by 2ζ/ω_n = 1 s, and on the helix in a cross current the crab angle turns by ±17° per
   132-s turn. So the filter is fed the rate of the corrections that the turning estimate ĉ (at
   fixed ν, θ) and the trims cause, ċ_ff, as ẍ = ω_n²(c − x) + 2ζω_n(ċ_ff − ẋ), which follows a
   ramp without lag. The paper's filter (ċ_ff absent) is unchanged when the option is off.

3. Adaptive LOS trims (``alos_y`` = γ_h, ``alos_z`` = γ_v; the ALOS laws of Fossen & Aguiar
   2024), with a capture gate g and projection onto [−M, M]:

       β̂̇ = γ_h g(|ε|) Δ_h y_e / √(Δ_h² + y_e²),    α̂̇ = γ_v g(|ε|) Δ_v z_e / √(Δ_v² + z_e²),
       g(d) = 1 / (1 + (d/R)⁴),   R = ``alos_radius``,   M = ``alos_max``.

   They absorb what the observer leaves: its lag behind a varying current, a bias the inner
   loop leaves (backstepping with a wrong model, or the mean drift that the white-noise forces
   rectify through the nonlinear damping), and the difference between body-frame errors and
   path-frame geometry on a curved path. Stability conditions relied on: Fossen & Aguiar prove
   USGES of (y_e, z_e, β̃, α̃) for a straight line, constant crab angles, U > 0 and perfect
   attitude tracking, for any γ > 0, Δ > 0 (here a cascade with the FBSM/backstepping loops,
   which converge exponentially on S = 0); Coates & Fossen (2025) drop the assumptions of
   constant depth and zero horizontal crab angle and extend USGES to a class of curved 3-D
   paths. The projection keeps β̂, α̂ bounded without changing that result while the true crab
   angles lie inside [−M, M]. The gate keeps the adaptation off during the approach: g ≤ 1/17
   beyond 2R and g ≈ 10⁻⁵ at the paper's start (|ε| = 17.7 m, R = 1 m). Outside the gate β̂, α̂
   are (nearly) constant and bounded by M, and the plain LOS with a constant crab-angle error
   β̃ is input-to-state stable: it brings y_e to within Δ_h tan|β̃| of the path. The observer
   makes β̃ small (it does not depend on the tracking error), so the vehicle enters the gate,
   where the ALOS result applies. Without the observer (pure ALOS) β̃ is the whole crab angle,
   ≈ 17° for 0.3 m/s at 1 m/s, and R must exceed Δ_h tan 17° ≈ 3 m, so that the trims learn
   on the approach (wind-up); that is why the observer carries the current and ALOS only trims.
   On a helix the crab angle a constant current needs rotates with the path, which a constant-
   parameter law can only chase; the observer follows it.

4. Speed over ground (``speed_over_ground``). The virtual point moves at u_p = u_D(1 +
   tanh(x_e/σ)) (docs/model.md §3.3), so it waits at x_e = 0 only if the vehicle makes u_D
   over ground along the path; with a current c along the path and surge u_D through the water
   it lags by x_e = σ artanh(c/u_D) (0.16 m for 0.3 m/s). The surge reference becomes the speed
   through the water that gives u_D over ground along t, and its rate is fed forward:

       u_ref = √((u_D − t·ĉ)² + |ĉ|² − (t·ĉ)²),   u̇_ref by finite difference over one step,

   limited to [max(u_D/2, |ĉ| + 0.2 u_D), 2u_D]. The lower bound keeps the vehicle faster
   through the water than the current: a following current would otherwise slow it below the
   current's speed, where the course over ground no longer follows the heading and crab-angle
   guidance loses the vehicle (the papers assume a speed through the water above the current's,
   e.g. U_r > V_max in Caharija et al. 2016); it costs an along-track lead x_e = σ artanh(·)
   of the surplus speed instead. In still water ĉ = 0 and u_ref = u_D exactly.

5. The current from the DVL (``dvl_current`` = ω_c > 0, in place of the observer). A DVL in
   bottom lock measures the velocity over ground ν_g = ν + c (docs/model.md §14.1), and the
   agents' observation (``observation="preview"``) carries it beside ν, so the current is
   measured, m = ν̂_g − ν̂, not inferred from the position errors. The simulated DVL gives both
   with one ping's error, so m = (1 + k)c exactly, with k the DVL's scale-factor error, and
   it holds the waves' orbital velocity at the vehicle (with a navigation ``delay`` ν is the
   delayed ping's and the velocity over ground the latest: m then mixes two pings,
   docs/model.md §3.7). The first step only initialises ĉ, so its jump feeds no crab-angle rate
   forward. ĉ follows m through a first-order
   low-pass at ω_c that turns with the body like the observer's estimate,

       ĉ̇ = −ω_b × ĉ + ω_c (m − ĉ),    ĉ(0) = m,

   Euler for the rotation and the exact step 1 − e^{−ω_c Δt_c} for the low-pass (stable at any
   ω_c). It reads no position error and no u_p, so neither the navigation's along-track error
   nor a virtual point that moves with the true x_e (docs/model.md §14.9) enters the estimate.
   The crab angles (2) and the speed over ground (4) use this ĉ as they use the observer's.

References: A. P. Aguiar, A. M. Pascoal (2007), Dynamic positioning and way-point tracking of
underactuated AUVs in the presence of ocean currents, Int. J. Control 80(7). S. Moe, W.
Caharija, K. Y. Pettersen, I. Schjølberg (2014), Path following of underactuated marine surface
vessels in the presence of unknown ocean currents, ACC. M. Maghenem, D. J. W. Belleter, C.
Paliotta, K. Y. Pettersen (2017), Observer based path following for underactuated marine vessels
in the presence of ocean currents: a global approach, IFAC World Congress. T. I. Fossen, A. P.
Aguiar (2024), A uniform semiglobal exponential stable adaptive line-of-sight (ALOS) guidance law
for 3-D path following, Automatica 163, 111556. E. M. Coates, T. I. Fossen (2025), A spherical
amplitude–phase formulation for 3-D adaptive line-of-sight (ALOS) guidance with USGES stability
guarantees, arXiv:2505.08344.
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
    "measure_current",
    "observe_current",
    "path_tangent",
    "speed_reference",
]

# Offsets in the guidance memory (`controllers.los.FILTER_DIM`): ε̂ [m], ĉ [m/s], the last
# measured part g of ε̇ [m/s] (3 each), β̂, α̂ [rad], u_ref [m/s].
EPS_HAT, C_HAT, G_PREV, BETA_HAT, ALPHA_HAT, U_REF = 8, 11, 14, 17, 18, 19
SPEED_MARGIN = 0.2  # u_ref ≥ |ĉ| + 0.2 u_D (module doc, 4)


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
def measure_current(u, v, w, u_g, v_g, w_g, q, r, theta, wn, dt, started, filt):
    """One step of the DVL current filter (module doc, 5) on ĉ in ``filt``: the measured
    current m = ν_g − ν [m/s] (velocities over ground and through the water, body axes)
    low-passed at ``wn`` [rad/s], turned with the body rates q, r [rad/s]."""
    mx, my, mz = u_g - u, v_g - v, w_g - w
    if not started:  # ĉ(0) = m
        filt[C_HAT], filt[C_HAT + 1], filt[C_HAT + 2] = mx, my, mz
        return
    tth = math.tan(theta)
    cx, cy, cz = filt[C_HAT], filt[C_HAT + 1], filt[C_HAT + 2]
    gain = 1.0 - math.exp(-wn * dt)
    # the rotation as in `observe_current`: −ω_b × ĉ with ω_b = (−r tanθ, q, r)
    cx += dt * (r * cy - q * cz)
    cy += dt * (-r * cx - r * tth * cz)
    cz += dt * (q * cx + r * tth * cy)
    filt[C_HAT] = cx + gain * (mx - cx)
    filt[C_HAT + 1] = cy + gain * (my - cy)
    filt[C_HAT + 2] = cz + gain * (mz - cz)


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
    speed2 = cx * cx + cy * cy + cz * cz
    u_ref = math.sqrt((u_d - along) ** 2 + max(speed2 - along * along, 0.0))
    # faster than the current, so that the course over ground still follows the heading
    lower = max(0.5 * u_d, math.sqrt(speed2) + SPEED_MARGIN * u_d)
    return min(max(u_ref, lower), 2.0 * u_d)


def guidance_diagnostics(gains, filt: np.ndarray) -> dict[str, np.ndarray]:
    """Extras for `auv_gym.rollout` from the guidance memory (n, FILTER_DIM), where switched
    on: ``current_hat`` (n, 3), the body-axis estimate ĉ [m/s]; ``beta_hat``, ``alpha_hat``
    (n,), the ALOS trims [rad]; ``u_ref`` (n,), the surge reference [m/s]."""
    out = {}
    if gains.current_observer > 0.0 or gains.dvl_current > 0.0:
        out["current_hat"] = filt[:, C_HAT : C_HAT + 3].copy()
    if gains.alos_y > 0.0 or gains.alos_z > 0.0:
        out["beta_hat"] = filt[:, BETA_HAT].copy()
        out["alpha_hat"] = filt[:, ALPHA_HAT].copy()
    if gains.speed_over_ground:
        out["u_ref"] = filt[:, U_REF].copy()
    return out
