"""``update_dtype: bfloat16``: the learner's minibatch passes run in bfloat16 while collection,
weights and the saved agent stay float32; bad values are one line naming the key."""

from __future__ import annotations

import pytest
import yaml

pytestmark = pytest.mark.rl


def _ppo(dtype: str):
    import torch
    from stable_baselines3 import PPO

    from auv_gym.sb3 import make_sb3_vec_env
    from benchmarks.training.update_precision import use_update_dtype

    torch.manual_seed(0)
    venv = make_sb3_vec_env(2, seed=5, max_time=20.0, observation="preview", infos="minimal")
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=32, n_epochs=2, seed=1, device="cpu",
                policy_kwargs={"net_arch": [32, 32]})  # fmt: skip
    use_update_dtype(model, dtype)
    return model


def test_the_update_runs_in_bfloat16_and_collection_in_float32():
    import torch

    model = _ppo("bfloat16")
    seen: list[tuple[bool, torch.dtype]] = []  # (inside the update, output dtype)
    in_update = [False]
    first_layer = model.policy.mlp_extractor.policy_net[0]
    first_layer.register_forward_hook(lambda m, i, o: seen.append((in_update[0], o.dtype)))
    update = model.train

    def flagged_update() -> None:
        in_update[0] = True
        try:
            update()
        finally:
            in_update[0] = False

    model.train = flagged_update
    model.learn(128)
    collection = {dtype for inside, dtype in seen if not inside}
    learner = {dtype for inside, dtype in seen if inside}
    assert collection == {torch.float32} and learner == {torch.bfloat16}
    # 2 rollouts of 2 × 32 steps: 2 epochs × 2 minibatches of 32 each
    assert len([1 for inside, _ in seen if inside]) == 2 * 2 * 2
    assert all(p.dtype == torch.float32 for p in model.policy.parameters())


def test_bfloat16_weights_differ_from_float32_by_rounding_only():
    import torch

    runs = {}
    for dtype in ("float32", "bfloat16"):
        model = _ppo(dtype)
        model.learn(64)
        runs[dtype] = torch.cat([p.detach().flatten() for p in model.policy.parameters()])
    diff = (runs["float32"] - runs["bfloat16"]).abs().max().item()
    # Adam's steps are ±lr-sized (3e-4) whatever the gradient's rounding: the runs part, within
    # a few steps' worth after 2 updates of 2 epochs.
    assert 0.0 < diff < 4 * 2 * 3e-4 * 1.01
    assert torch.isfinite(runs["bfloat16"]).all()


@pytest.mark.parametrize("value", ["fp16", "float64", 16, None, True])
def test_a_bad_update_dtype_is_one_line_naming_it(tmp_path, value):
    from benchmarks.training.config import read_zoo_config

    section = {"n_envs": 2, "n_timesteps": 64, "policy": "MlpPolicy", "normalize": True,
               "n_steps": 32, "batch_size": 32, "update_dtype": value}  # fmt: skip
    path = tmp_path / "c.yml"
    path.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    with pytest.raises(ValueError, match=r"AUVPath3DPreview-v0: update_dtype must be one of "
                                         r"\['float32', 'bfloat16'\], got"):  # fmt: skip
        read_zoo_config(path, "AUVPath3DPreview-v0", "ppo")
    section["update_dtype"] = "bfloat16"
    path.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    assert read_zoo_config(path, "AUVPath3DPreview-v0", "ppo").update_dtype == "bfloat16"
    del section["update_dtype"]
    path.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    assert read_zoo_config(path, "AUVPath3DPreview-v0", "ppo").update_dtype == "float32"


def test_a_bfloat16_run_saves_and_exports_a_float32_agent(tmp_path, train_tiny_preview_agent):
    import json

    import torch

    from controllers.loader import load_policy

    agent = train_tiny_preview_agent(tmp_path, update_dtype="bfloat16")
    assert json.loads((agent / "metadata.json").read_text())["update_dtype"] == "bfloat16"
    policy = load_policy(agent)
    assert all(p.dtype == torch.float32 for p in policy.sb3_policy.parameters())
