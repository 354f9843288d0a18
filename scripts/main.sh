#!/usr/bin/env bash
# The main job: set-up (idempotent), then a quick FBSM vs backstepping vs PPO comparison (plus the
# integral-LOS and current-observer-LOS variants of the classical two, FBSM + CO-LOS through a
# low-pass filter, the generalist PPO (both generations) and SAC, and the residual PPO on top of FBSM + CO-LOS) on
# every scenario (3 seeds, 150-s episodes; a few minutes
# on 2 cores) -> out/quick/{summary.md,figures/}.
# The full-size run that produced benchmarks/results/ is in the README.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. .venv/bin/activate
python -m benchmarks.compare \
    --policies fbsm,backstepping,ppo,fbsm_ilos,backstepping_ilos,fbsm_colos,backstepping_colos,fbsm_colos_lowpass,ppo_generalist,ppo_preview,sac_generalist,ppo_residual \
    --scenarios all --seeds 3 --duration 150 --out out/quick "$@"
