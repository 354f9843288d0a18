#!/usr/bin/env bash
# Set-up, once: a virtual environment in .venv with torch 2.13.0 and every extra, then the
# simulation kernels compiled and cached. A re-run skips pip when pyproject.toml and this script
# are unchanged and the packages import, and skips compiling when the kernel cache is current.
#
# torch comes first, pinned, so that stable-baselines3 never pulls a torch of its own choosing.
# Which build pip installs depends on the index: the public PyPI serves the CUDA build of
# torch 2.13.0 on Linux (several GB); for the CPU build, point pip at PyTorch's CPU index:
#     TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu bash scripts/setup.sh
# (this project's CI machines have the CPU wheel in their package mirror, so the default works
# there).
set -euo pipefail
cd "$(dirname "$0")/.."
stamp=".venv/.setup-stamp"
wanted="$(cat pyproject.toml scripts/setup.sh | sha256sum | cut -d' ' -f1)"
if [ ! -x .venv/bin/python ]; then
    echo "set-up: creating .venv" >&2
    python3 -m venv .venv
fi
. .venv/bin/activate
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wanted" ] \
    && python -c "import auv_gym, controllers, benchmarks, torch, stable_baselines3" 2>/dev/null; then
    echo "set-up: packages up to date (pip skipped)" >&2
else
    echo "set-up: installing torch 2.13.0 (CPU) and auv-gym with its extras (a few minutes)" >&2
    python -m pip install -q --upgrade pip
    if [ -n "${TORCH_INDEX_URL:-}" ]; then
        python -m pip install -q "torch==2.13.0" --index-url "$TORCH_INDEX_URL"
    else
        python -m pip install -q "torch==2.13.0"
    fi
    python -m pip install -q -e ".[rl,test,ray,stats,video,onnx,mcap]"
    python -c "import torch; print(f'set-up: torch {torch.__version__}, CUDA build: {torch.version.cuda is not None}')" >&2
    echo "$wanted" > "$stamp"
fi
python -m benchmarks.runner.compile_kernels
