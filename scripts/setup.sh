#!/usr/bin/env bash
# One-time set-up: a virtual environment in .venv with torch 2.13.0 and every extra.
#
# torch comes first, pinned, so that stable-baselines3 never pulls a torch of its own choosing.
# Which build pip installs depends on the index: the public PyPI serves the CUDA build of
# torch 2.13.0 on Linux (several GB); for the CPU build, point pip at PyTorch's CPU index:
#     TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu bash scripts/setup.sh
# (this project's CI machines have the CPU wheel in their package mirror, so the default works
# there). The script prints the build it ended with.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
. .venv/bin/activate
python -m pip install -q --upgrade pip
if [ -n "${TORCH_INDEX_URL:-}" ]; then
    python -m pip install -q "torch==2.13.0" --index-url "$TORCH_INDEX_URL"
else
    python -m pip install -q "torch==2.13.0"
fi
python -m pip install -q -e ".[rl,test,ray,stats,video]"
python -c "import torch; print(f'set-up done: torch {torch.__version__}, CUDA build: {torch.version.cuda is not None}')"
