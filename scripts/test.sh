#!/usr/bin/env bash
# The test suite: set-up (idempotent), lint, then every test on both cores.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. .venv/bin/activate
ruff check .
ruff format --check .
python -m pytest -q -n 2 "$@"
