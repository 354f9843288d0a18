"""The info dicts of both envs, pinned: keys, their order, types, dtypes and values.

The digests were recorded from the envs' output before the info was built by one shared
function; every key (reward terms, cost, termination_reason, the vector env's masks and
final_info on autoreset) enters the digest with its type, dtype, shape and bytes.
"""

from __future__ import annotations

import hashlib
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import auv_gym  # noqa: F401  (registers the ids)

# Episodes that end within a few steps: a corridor just above the initial 17.7 m distance and
# random starts (some vehicles terminate, some run into the short horizon).
SHORT = {"corridor": 18.0, "max_time": 0.5, "randomize_start": True}


def _feed(digest: Any, value: Any) -> None:
    digest.update(type(value).__name__.encode())
    if isinstance(value, dict):
        for key, item in value.items():
            digest.update(repr(key).encode())
            _feed(digest, item)
    elif isinstance(value, np.ndarray):
        digest.update(f"{value.dtype.str}{value.shape}".encode())
        if value.dtype == object:
            for item in value:
                _feed(digest, item)
        else:
            digest.update(np.ascontiguousarray(value).tobytes())
    else:
        digest.update(repr(value).encode())


def _actions(seed: int, steps: int, n: int) -> np.ndarray:
    a = np.random.default_rng(seed).uniform(-1, 1, size=(steps, n, 3)).astype(np.float32)
    a[..., 0] = 0.6 * a[..., 0] - 0.1  # often astern: the corridor ends some episodes
    return a


def _single_digest() -> tuple[str, set[str]]:
    digest, reasons = hashlib.sha256(), set()
    env = gym.make("AUVPath3D-v0", **SHORT).unwrapped
    actions = _actions(0, 60, 1)
    for seed in range(3):
        _, info = env.reset(seed=seed)
        _feed(digest, info)
        for a in actions:
            _, _, terminated, truncated, info = env.step(a[0])
            _feed(digest, info)
            if terminated or truncated:
                reasons.add(info.get("termination_reason", "truncated"))
                break
    return digest.hexdigest(), reasons


def _vector_digest(mode: AutoresetMode) -> tuple[str, set[str]]:
    digest, keys = hashlib.sha256(), set()
    env = gym.make_vec(
        "AUVPath3D-v0",
        num_envs=4,
        vectorization_mode="vector_entry_point",
        autoreset_mode=mode,
        **SHORT,
    )
    _, infos = env.reset(seed=5)
    _feed(digest, infos)
    for a in _actions(1, 25, 4):
        *_, infos = env.step(a)
        _feed(digest, infos)
        keys |= set(infos) | set(infos.get("final_info", ()))
    env.close()
    return digest.hexdigest(), keys


def test_single_env_info_is_unchanged():
    digest, reasons = _single_digest()
    assert reasons == {"corridor", "truncated"}
    assert digest == "902255464e16a91319ac7ff81efcc6c294d837da7b93100640a7d4dc6c8c1060"


_VECTOR_DIGESTS = {
    AutoresetMode.NEXT_STEP: "e3aeb8ec85e3e202de14b85facf908ba48c99752deab18826e1258fac8f134f7",
    AutoresetMode.SAME_STEP: "be972551b76b62538c7438d0667032feada7476ed08ecdef478b8810b2b0d1c9",
    AutoresetMode.DISABLED: "9b2194f0bbbb59c02ddaa1a06644480ee97d047dda6d010183eb98889c63ce66",
}


@pytest.mark.parametrize("mode", list(_VECTOR_DIGESTS))
def test_vector_env_info_is_unchanged(mode):
    digest, keys = _vector_digest(mode)
    assert {"cost", "termination_reason", "reward_progress"} <= keys
    if mode is AutoresetMode.SAME_STEP:
        assert "final_info" in keys
    assert digest == _VECTOR_DIGESTS[mode]
