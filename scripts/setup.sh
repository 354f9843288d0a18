#!/usr/bin/env bash
# Set-up, once: a virtual environment in .venv with torch 2.13.0 and every extra, then the
# simulation kernels compiled and cached. A re-run skips pip when pyproject.toml and this script
# are unchanged and the packages import, and skips compiling when the kernel cache is current.
#
# torch comes first, pinned, so that stable-baselines3 never pulls a torch of its own choosing.
# Which build pip installs depends on the index: PyTorch's CPU index is tried first (the CPU
# build); where it cannot be reached, pip's configured index (the public PyPI serves the CUDA
# build of torch 2.13.0 on Linux, several GB; this project's CI mirror serves the CPU build).
# TORCH_INDEX_URL chooses the index outright:
#     TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu bash scripts/setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."
stamp=".venv/.setup-stamp"
CPU_INDEX="https://download.pytorch.org/whl/cpu"  # tried first: torch's CPU build
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
    echo "set-up: installing torch 2.13.0 and auv-gym with its extras (about 3 min, 2.2 GB)" >&2
    python -m pip install -q --upgrade pip
    if [ -n "${TORCH_INDEX_URL:-}" ]; then
        echo "set-up: torch from $TORCH_INDEX_URL" >&2
        python -m pip install -q "torch==2.13.0" --index-url "$TORCH_INDEX_URL"
    elif timeout 10 python -c "import urllib.request as u; u.urlopen('$CPU_INDEX/torch/', timeout=5)" \
        2>/dev/null; then  # reachable: pip alone can hang for minutes on an unreachable index
        echo "set-up: torch's CPU build from $CPU_INDEX" >&2
        python -m pip install -q "torch==2.13.0" --index-url "$CPU_INDEX"
    else  # PyTorch's index unreachable: the configured index (a mirror may serve the CPU build)
        echo "set-up: $CPU_INDEX unreachable; torch from pip's configured index (the public" \
            "PyPI serves the CUDA build, several GB)" >&2
        python -m pip install -q "torch==2.13.0"
    fi
    python -m pip install -q -e ".[rl,test,ray,stats,video,onnx,mcap]"
    python -c "import torch; print(f'set-up: torch {torch.__version__}, CUDA build: {torch.version.cuda is not None}')" >&2
    echo "$wanted" > "$stamp"
fi
python -m benchmarks.runner.compile_kernels
