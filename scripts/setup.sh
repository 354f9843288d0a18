#!/usr/bin/env bash
# One-time set-up: a virtual environment in .venv with the CPU build of torch and every extra.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
. .venv/bin/activate
python -m pip install -q --upgrade pip
# Pin the CPU wheel first so that stable-baselines3 never pulls a multi-GB CUDA torch.
python -m pip install -q "torch==2.13.0"
python -m pip install -q -e ".[rl,test,ray,stats,video]"
