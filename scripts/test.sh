#!/usr/bin/env bash
# The test suite: set-up (idempotent), lint, then the tests on both cores.
#   bash scripts/test.sh                  # every test but the integration tier (about 6 min
#                                         # on 2 cores after set-up; the 15 slowest are listed)
#   bash scripts/test.sh --integration    # the integration tier alone: fresh installs, baseline
#                                         # trees, Ray, recompiles, commands end to end (about 5 min)
# Other arguments go to pytest. CI runs both (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. .venv/bin/activate
# The kernels of every benchmark scenario, not only the main job's (once; then instant).
python -m benchmarks.runner.compile_kernels --all
ruff check .
ruff format --check .
if [ "${1:-}" = "--integration" ]; then
    shift
    python -m pytest -q -n 2 --durations=15 -m integration "$@"
else
    python -m pytest -q -n 2 --durations=15 -m "not integration" "$@"
fi
