#!/usr/bin/env bash
# The main job: set-up (once; re-runs skip what is current), then the reference policies on the
# scenarios that tell them apart, 3 seeds x 150 s each (about 1.5 min on 2 cores once compiled):
#   classical: the paper's FBSM and backstepping, FBSM with current-observer LOS, PID + LOS;
#   learned:   the PPO generalist, the residual PPO on FBSM + CO-LOS, the SAC generalist
#              (benchmarks/agents/README.md);
#   scenarios: the paper's helix, a cross current, the fin-limited vehicle, a waypoint spline,
#              a storm (noise, current and 30 % parameter error together), the propeller and
#              fins as built (benchmarks/scenarios.toml).
# It prints a one-screen overview and where the files are: out/quick/{summary.md,episodes.csv,
# figures/}. The full-size runs behind benchmarks/results/ are in docs/results.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. .venv/bin/activate
python -m benchmarks.runner.compare \
    --policies fbsm,fbsm_colos,backstepping,pid_los,ppo_generalist,ppo_residual,sac_generalist \
    --scenarios paper,current,fins,waypoints,storm,realistic_actuators \
    --seeds 3 --duration 150 --out out/quick "$@"
