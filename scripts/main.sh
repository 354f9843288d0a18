#!/usr/bin/env bash
# The main job: set-up (idempotent), then a quick comparison on every scenario (3 seeds, 150-s
# episodes; a few minutes on 2 cores) -> out/quick/{summary.md,figures/}: the paper's FBSM and
# backstepping, a textbook PID + LOS autopilot, their integral-LOS and current-observer-LOS
# variants, FBSM + CO-LOS through a low-pass filter, the PPO specialist, the generalist PPO
# (four generations; the fourth trained on the paper's actuator for 5M env steps, bare and
# inside its envelope guard, and for 8M inside it, also with its moments allocated to the
# scenario's actuator, and that agent after an along-track and then a cross-track phase) and SAC
# (two generalists, the second trained inside the envelope guard and allocated, and the helix
# specialist with error integrals), and the residual PPO on top of FBSM + CO-LOS.
# The full-size runs that produced benchmarks/results/ are in docs/results.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. .venv/bin/activate
python -m benchmarks.compare \
    --policies fbsm,backstepping,pid_los,pid_colos,ppo,fbsm_ilos,backstepping_ilos,fbsm_colos,backstepping_colos,fbsm_colos_lowpass,ppo_generalist,ppo_preview,ppo_integral,ppo_antiwindup,ppo_paper_actuator,ppo_paper_actuator_guard,ppo_paper_start_guard,ppo_paper_start_guard_alloc,ppo_along_track_guard_alloc,ppo_cross_track_guard_alloc,sac_generalist,sac_paper_actuator_guard_alloc,sac_helix,ppo_residual \
    --scenarios all --seeds 3 --duration 150 --out out/quick "$@"
