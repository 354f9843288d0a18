"""Exported agents (ONNX): each graph piece against its numpy original, the shipped exports, the
closed loop against the Python agent, a runtime without torch, and bad input refused up front."""

from __future__ import annotations

import importlib.util
import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("onnx")

import controllers
from auv_gym.sim.observation import ObservationConfig
from auv_gym.vehicle.actuators import ActuatorParams
from benchmarks.catalog.policies import AGENTS_DIR, REFERENCE_AGENTS, policy_env
from controllers.actuator_allocation import Allocation
from controllers.agent import check_agent
from controllers.envelope_guard import EnvelopeGuard, guard_commands
from controllers.onnx_graph import (
    OPSET,
    Graph,
    allocation_graph,
    guard_graph,
    normalisation_graph,
    residual_graph,
)
from controllers.onnx_policy import read_contract, sha256_of
from controllers.residual import RESIDUAL_FEATURES, residual_action

ROOT = Path(__file__).resolve().parents[1]
# onnxruntime is imported by the project only (`onnxruntime_module`: telemetry off)
pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("onnxruntime") is None, reason="needs onnxruntime"
)
NAMES = ObservationConfig.from_spec("preview_integral").names


def run_graph(g: Graph, inputs: dict[str, np.ndarray], outputs: list[str]) -> list[np.ndarray]:
    """Run the graph ``g`` on float32 ``inputs`` (n, k) with onnxruntime; its named outputs."""
    from onnx import TensorProto, checker, helper

    from controllers.onnx_policy import onnxruntime_module

    onnxruntime = onnxruntime_module()

    ins = [
        helper.make_tensor_value_info(k, TensorProto.FLOAT, ["n", v.shape[1]])
        for k, v in inputs.items()
    ]
    outs = [helper.make_tensor_value_info(name, TensorProto.FLOAT, ["n", None]) for name in outputs]
    graph = helper.make_graph(g.nodes, "piece", ins, outs, g.initializers)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)])
    model.ir_version = 8
    checker.check_model(model, full_check=True)
    session = onnxruntime.InferenceSession(
        model.SerializeToString(), providers=["CPUExecutionProvider"]
    )
    return session.run(outputs, inputs)


def operating_observations(n: int, rng: np.random.Generator) -> np.ndarray:
    """Observations (n, 49) spread over and beyond the envelope: pitch to ±70°, q to ±0.5 rad/s,
    surge −0.5 to 2.5 m/s, sway and heave ±0.5 m/s (u = 0 in some rows: no flow over the fins)."""
    obs = rng.normal(0.0, 1.0, (n, len(NAMES))).astype(np.float32)
    col = {name: NAMES.index(name) for name in ("theta", "q", "u", "v", "w")}
    obs[:, col["theta"]] = rng.uniform(-1.2, 1.2, n)
    obs[:, col["q"]] = rng.uniform(-0.5, 0.5, n)
    obs[:, col["u"]] = rng.uniform(-0.5, 2.5, n)
    obs[:10, col["u"]] = 0.0
    obs[:, col["v"]] = rng.uniform(-0.5, 0.5, n)
    obs[:, col["w"]] = rng.uniform(-0.5, 0.5, n)
    return obs


@pytest.mark.parametrize(
    ("nose_up_command", "floor"), [(1.0, (0.0, 0.0)), (-1.0, (0.0, 0.0)), (-1.0, (1.2, 0.9))]
)
def test_the_guard_graph_is_guard_commands(nose_up_command, floor):
    rng = np.random.default_rng(1)
    obs = operating_observations(4000, rng)
    commands = rng.uniform(-1.0, 1.0, (4000, 3)).astype(np.float32)
    guard = EnvelopeGuard(
        nose_up_command=nose_up_command, surge_floor_soft=floor[0], surge_floor_hard=floor[1]
    )
    index = [NAMES.index(n) for n in ("theta", "q", "u")]
    g = Graph()
    guard_graph(g, "commands", "observation", index, guard)
    g.op("Identity", g.nodes[-1].output[0], output="out")
    (got,) = run_graph(g, {"commands": commands, "observation": obs}, ["out"])
    want = guard_commands(commands, obs, index, guard)
    assert np.abs(want - commands).max() > 0.5  # the guard acted on many rows
    if guard.has_floor:  # and the floor on the slow ones
        slow = obs[:, index[2]] < 0.9
        assert np.all(want[slow, 0] == 1.0) and np.any(commands[slow, 0] < 0.0)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)


@pytest.mark.parametrize(
    ("actuator", "induced_drag"), [("fins", 1.0), ("realistic", 1.0), ("realistic", 0.0)]
)
def test_the_allocation_graph_is_the_allocation(actuator, induced_drag):
    """Also with the torpedo's fins (no induced drag, κ = 0): the graph's allocation takes κ."""
    rng = np.random.default_rng(2)
    obs = operating_observations(4000, rng)
    commands = rng.uniform(-1.2, 1.2, (4000, 3)).astype(np.float32)
    params = ActuatorParams(fin_induced_drag=induced_drag)
    allocation = Allocation(NAMES, actuator, actuator_params=params)
    g = Graph()
    out, delivered = allocation_graph(g, "commands", "observation", allocation)
    g.op("Identity", out, output="out")
    g.op("Identity", delivered, output="delivered")
    got, got_delivered = run_graph(
        g, {"commands": commands, "observation": obs}, ["out", "delivered"]
    )
    want, want_delivered = allocation.allocate(commands, obs)
    assert np.mean(np.abs(want) >= 1.0) > 0.005  # saturated rows are covered
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)
    np.testing.assert_allclose(got_delivered, want_delivered, rtol=0, atol=1e-6)


def test_the_residual_and_normalisation_graphs_are_their_numpy_forms():
    rng = np.random.default_rng(3)
    n = 3000
    base, previous = (rng.uniform(-1, 1, (n, 3)).astype(np.float32) for _ in range(2))
    correction = rng.uniform(-1.5, 1.5, (n, 6)).astype(np.float32)
    started = rng.integers(0, 2, (n, 1)).astype(np.float32)
    g = Graph()
    out = residual_graph(g, "base", "correction", "previous", "started", (0.25, 0.5, 0.5), 0.8)
    g.op("Identity", out, output="out")
    feeds = {"base": base, "correction": correction, "previous": previous, "started": started}
    (got,) = run_graph(g, feeds, ["out"])
    want = residual_action(base, correction, (0.25, 0.5, 0.5), 0.8, previous, started[:, 0] > 0)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)

    obs = rng.normal(0, 3, (n, 5)).astype(np.float32)
    mean, var = rng.normal(0, 1, 5), rng.uniform(0.0, 4.0, 5)
    g = Graph()
    g.op("Identity", normalisation_graph(g, "obs", mean, var, 5.0, 1e-8), output="out")
    (got,) = run_graph(g, {"obs": obs}, ["out"])
    want = np.clip((obs - mean) / np.sqrt(var + 1e-8), -5.0, 5.0).astype(np.float32)
    assert np.any(np.abs(want) == 5.0)
    np.testing.assert_array_equal(got, want)  # float64 in both: the same roundings


@pytest.mark.parametrize("agent", REFERENCE_AGENTS)
def test_every_reference_agent_ships_a_current_export(agent):
    import onnx

    folder = AGENTS_DIR / agent
    contract = read_contract(folder / "policy.onnx")
    raw = contract.raw
    files = check_agent(folder)
    members = files.members or (files,)  # an ensemble's graph holds each member's network
    provenance = raw["provenance"].get("members", [raw["provenance"]])
    assert [p["model_sha256"] for p in provenance] == [sha256_of(m.model) for m in members]
    assert raw["parity"]["max_abs_error"] <= 1e-5 and raw["parity"]["observations"] >= 2048
    env_id, _ = policy_env(agent)
    assert contract.env_id == env_id
    metadata = files.metadata
    names = metadata["obs_names"]  # a residual's end with its base's command and its previous one
    expected = names[: -len(RESIDUAL_FEATURES)] if "residual" in metadata else names
    assert list(contract.obs_names) == expected
    props = {p.key: p.value for p in onnx.load(folder / "policy.onnx").metadata_props}
    assert props["env_id"] == env_id
    assert json.loads(props["observation_names"]) == expected
    own = metadata.get("env_kwargs", {}).get("actuator") == "realistic"  # ppo_as_built
    assert props["actuator"] == raw["actuator"] == ("realistic" if own else "paper")
    assert float(props["control_period_s"]) == raw["control_period_s"] == 0.05
    # everything the graph was built for, in the contract and the graph alike
    assert raw["format_version"] == 2 and props["plant"] == raw["plant"] == "5dof"
    assert json.loads(props["env_kwargs"]) == raw["env_kwargs"]
    assert raw["env_kwargs"].get("actuator", "paper") == raw["actuator"]
    assert json.loads(props["stage_settings"]) == raw["stages"]
    assert json.loads(props["actuator_params"]) is raw["actuator_params"] is None
    assert json.loads(props["allocation"]) is raw["allocation"] is None  # none on its actuator
    assert json.loads(props["allocated"]) is raw["allocated"]


@pytest.mark.parametrize("agent", REFERENCE_AGENTS)
def test_shipped_contracts_hold_no_machine_paths(agent):
    """Was: the exporting machine's absolute paths and training files outside the repository."""
    raw = json.loads((AGENTS_DIR / agent / "policy.json").read_text())

    def strings(value):
        if isinstance(value, dict):
            for k, v in value.items():
                yield k
                yield from strings(v)
        elif isinstance(value, list):
            for v in value:
                yield from strings(v)
        elif isinstance(value, str):
            yield value

    found = list(strings(raw))
    assert len(found) > 90  # names, units, provenance: the walk reached them
    for text in found:
        assert not text.startswith(("/", "~")) and not Path(text).is_absolute(), text
        assert not any(root in text for root in ("/root", "/work", "/tmp", "/home")), text
    assert raw["provenance"]["agent"] == agent
    config = raw["provenance"].get("config_file")
    assert config is None or (ROOT / config).is_file()  # a file of this repository


@pytest.mark.rl
@pytest.mark.integration  # an export and four 200-s episodes per agent
@pytest.mark.parametrize(
    ("agent", "env"),
    [
        # the paper's ±35 N·m noise is ten times the fins' authority: the noise-free helix
        ("ppo_generalist", {"actuator": "fins", "disturbance": "none"}),
        ("ppo_residual", {"disturbance": "paper", "current": {"mean": [0.2, 0.1, 0.0]}}),
        ("sac_generalist", {"disturbance": "paper"}),
    ],
)
def test_an_export_flies_like_its_agent(tmp_path, agent, env):
    from auv_gym import VARIANTS
    from auv_gym.rollout import evaluate
    from benchmarks.runner.export import main as export

    actuator = env.get("actuator", "paper")
    onnx_file = tmp_path / "agent.onnx"
    result = export([agent, "--out", str(onnx_file), "--actuator", actuator])
    assert result["max_abs_error"] <= 1e-5
    env_id, own = policy_env(agent)
    # 200 s: the generalist reaches the calm fins helix late (3.3 m RMS over 60-120 s, 0.031 m
    # over 100-200 s)
    kwargs = {**VARIANTS[env_id], **own, **env, "max_time": 200.0}
    python = controllers.make("agent", env=kwargs, path=str(AGENTS_DIR / agent))
    exported = controllers.make("onnx", env=kwargs, path=str(onnx_file))
    a = evaluate(python, [0, 1], transient=100.0, **kwargs)
    b = evaluate(exported, [0, 1], transient=100.0, **kwargs)
    for x, y in zip(a, b, strict=True):
        assert x["rms_distance"] < 0.5  # on the path after the approach
        assert y["rms_distance"] == pytest.approx(x["rms_distance"], rel=1e-3)


@pytest.mark.integration  # a subprocess flying a 150-s episode
def test_the_documented_runtime_flies_without_torch(tmp_path):
    text = (ROOT / "docs" / "usage.md").read_text(encoding="utf-8")
    code = text.split("<!-- onnx-example -->\n```python\n")[1].split("```")[0]
    assert len(code.strip().splitlines()) <= 40
    script = tmp_path / "fly.py"
    script.write_text(
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in ('torch', 'stable_baselines3', 'sb3_contrib'):\n"
        "            raise ImportError(f'{name} is blocked')\n"
        "sys.meta_path.insert(0, Block())\n"
        + code
        + "\nassert not {'torch', 'stable_baselines3'} & set(sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, str(script)], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    rms = float(done.stdout.split("last half: ")[1].split(" m")[0])
    assert 0.01 < rms < 0.1  # the generalist's few centimetres


def _agent_copy(tmp_path: Path, agent: str = "ppo_generalist") -> Path:
    copy = tmp_path / agent
    shutil.copytree(AGENTS_DIR / agent, copy)
    return copy


@pytest.mark.parametrize(
    "problem", ["unknown stage", "no statistics", "missing folder", "file as folder", "folder"]
)
def test_bad_exports_are_one_line_with_nothing_written(tmp_path, problem, auv_gym_command):
    agent = _agent_copy(tmp_path)
    out = tmp_path / "out" / "agent.onnx"
    out.parent.mkdir()
    if problem == "unknown stage":
        meta = json.loads((agent / "metadata.json").read_text())
        meta["stages"].append({"name": "lowpass"})
        (agent / "metadata.json").write_text(json.dumps(meta))
        expected = f"{agent}/metadata.json: unknown stage 'lowpass'"
    elif problem == "no statistics":
        (agent / "vecnormalize.npz").unlink()
        (agent / "vecnormalize.pkl").unlink()
        expected = "normalisation statistics missing"
    elif problem == "missing folder":
        out = tmp_path / "nowhere" / "agent.onnx"
        expected = f"folder {out.parent} does not exist"
    elif problem == "file as folder":  # was: "folder ... does not exist"
        (tmp_path / "afile").write_text("mine")
        out = tmp_path / "afile" / "agent.onnx"
        expected = f"--out {out}: {out.parent} is a file, not a folder"
    else:
        out.mkdir()
        expected = f"--out {out} is a folder, not a file"
    code, err = auv_gym_command("export", str(agent), "--out", str(out))
    assert code == 2
    assert len(err.splitlines()) == 1 and expected in err, err
    if problem == "file as folder":
        assert (tmp_path / "afile").read_text() == "mine"
    elif problem == "folder":
        assert list(out.iterdir()) == [] and list(out.parent.iterdir()) == [out]
    else:
        assert not out.parent.exists() or list(out.parent.iterdir()) == []


def test_an_export_older_than_the_agent_beside_it_is_refused(tmp_path):
    """Was: retraining (or replacing) an agent left its policy.onnx beside it, which flew the
    old networks without a word."""
    from controllers.onnx_contract import sha256_of
    from controllers.onnx_policy import OnnxPolicy

    agent = _agent_copy(tmp_path)
    OnnxPolicy(agent / "policy.onnx")  # the shipped export: its model, accepted
    old = sha256_of(agent / "model.zip")
    shutil.copy(AGENTS_DIR / "ppo_as_built" / "model.zip", agent / "model.zip")  # "retrained"
    new = sha256_of(agent / "model.zip")
    with pytest.raises(ValueError) as error:
        controllers.make("onnx", path=str(agent / "policy.onnx"))
    assert str(error.value) == (
        f"{agent / 'policy.onnx'} is stale: it was exported from a model with SHA-256 "
        f"{old[:12]}…, {agent / 'model.zip'} beside it has {new[:12]}… (retrained or replaced "
        f"after the export): re-export it (auv-gym export {agent} --out "
        f"{agent / 'policy.onnx'}) or move it out of the agent's folder"
    )
    deployed = tmp_path / "deployed"  # the graph and its contract alone: nothing to compare
    deployed.mkdir()
    for name in ("policy.onnx", "policy.json"):
        shutil.copy(agent / name, deployed / name)
    assert OnnxPolicy(deployed / "policy.onnx").obs_dim == 49  # the generalist's observation


def test_a_damaged_or_mismatched_export_is_refused_before_any_episode(tmp_path, auv_gym_command):
    for name in ("policy.onnx", "policy.json"):
        shutil.copy(AGENTS_DIR / "ppo_generalist" / name, tmp_path / name)
    onnx_file, contract_file = tmp_path / "policy.onnx", tmp_path / "policy.json"
    contract = json.loads(contract_file.read_text())
    contract["observation"]["names"] = contract["observation"]["names"] + ["a_X_prev"]
    contract_file.write_text(json.dumps(contract))
    out = tmp_path / "run"
    code, err = auv_gym_command(
        "compare",
        "--policies",
        f"fbsm,onnx:{onnx_file}",
        "--seeds",
        "1",
        "--duration",
        "20",
        "--scenarios",
        "paper",
        "--out",
        str(out),
    )
    assert code == 2 and len(err.splitlines()) == 1, err
    assert f"{onnx_file}" in err and "50 values" in err and "'n', 50" in err
    assert not out.exists()

    data = bytearray(onnx_file.read_bytes())
    data[len(data) // 2] ^= 0xFF
    onnx_file.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"does not match its contract .* \(SHA-256 differs"):
        controllers.make("onnx", path=str(onnx_file))


def test_the_runtime_checks_the_env_and_its_input():
    path = str(AGENTS_DIR / "ppo_generalist" / "policy.onnx")
    env = {"observation": "preview_integral", "surge_limit": "vehicle"}
    with pytest.raises(ValueError, match="exported for actuator 'paper', the env has 'fins'"):
        controllers.make("onnx", path=path, env={**env, "actuator": "fins"})
    with pytest.raises(ValueError, match=r"acts every 0\.05 s, the env every 0\.1 s"):
        controllers.make("onnx", path=path, env={**env, "control_dt": 0.1})
    with pytest.raises(ValueError, match=r"takes observations of 49 values .* the env gives 15"):
        controllers.make("onnx", path=path, env={})
    policy = controllers.make("onnx", path=path, env=env)
    with pytest.raises(ValueError, match=r"shape \(49,\) or \(n, 49\)"):
        policy.predict(np.zeros(15, np.float32))
    bad = np.zeros((2, 49), np.float32)
    bad[1, 3] = np.nan
    with pytest.raises(ValueError, match="observation row 1 is not finite"):
        policy.predict(bad)
    action, state = policy.predict(np.zeros((2, 49), np.float32))
    assert action.shape == (2, 3) and action.dtype == np.float32
    assert np.all(np.abs(action) <= 1.0) and state.n == 2


@pytest.mark.parametrize(
    ("agent", "options", "expected"),
    [
        # actuator settings where no allocation to the propeller and fins reads them
        ("ppo_generalist", ["--actuator-params", '{"rpm_max": 1400}'], "with --actuator paper"),
        (
            "ppo_generalist",
            ["--actuator", "fins", "--actuator-params", '{"rpm_max": 1400}'],
            "with --actuator fins there is no propeller to configure",
        ),
        (
            "ppo_as_built",
            ["--actuator-params", '{"rpm_max": 1400}'],
            "{meta} lists no actuator_allocation stage for them to change",
        ),
        (
            "ppo_generalist",
            ["--actuator", "realistic", "--actuator-params", '{"fin_rate_max": 0.9}'],
            "--actuator-params ['fin_rate_max']: the allocation does not read them",
        ),
        (
            "ppo_generalist",
            ["--actuator", "realistic", "--actuator-params", '{"rpm": 1}'],
            "--actuator-params: ",
        ),
    ],
)
def test_export_options_that_would_not_change_the_graph_are_refused(
    tmp_path, capsys, agent, options, expected
):
    """Was: --actuator fins on an agent without an allocation relabelled its commands, and
    --actuator-params with paper or fins were ignored."""
    from benchmarks.runner.export import main as export

    out = tmp_path / "agent.onnx"
    with pytest.raises(SystemExit) as exit_:
        export([agent, "--out", str(out), *options])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and len(err.splitlines()) == 1, err
    assert expected.format(meta=AGENTS_DIR / agent / "metadata.json") in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.rl
@pytest.mark.parametrize(
    ("actuator", "expected"),
    [
        ("fins", "--actuator fins: {meta} lists no actuator_alloc"),
        ("realistic", "--actuator realistic: {meta} lists no"),
    ],
)
def test_an_actuator_for_an_agent_without_an_allocation_is_refused(
    tmp_path, capsys, tiny_paper_agent, actuator, expected
):
    """No allocation stage: the graph would be the same, its commands relabelled."""
    from benchmarks.runner.export import main as export

    out = tmp_path / "out"
    out.mkdir()
    with pytest.raises(SystemExit) as exit_:
        export([str(tiny_paper_agent), "--out", str(out / "agent.onnx"), "--actuator", actuator])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and len(err.splitlines()) == 1, err
    assert expected.format(meta=tiny_paper_agent / "metadata.json") in err, err
    assert list(out.iterdir()) == []


@pytest.fixture(scope="module")
def exports_for_other_actuators(tmp_path_factory):
    """ppo_generalist exported for the fins, and for the propeller and fins with a 1400-rpm
    shaft limit (two exports, about 4 s each)."""
    pytest.importorskip("stable_baselines3")
    from controllers.onnx_export import export_onnx

    folder = tmp_path_factory.mktemp("exports")
    agent = AGENTS_DIR / "ppo_generalist"
    fins, _, _ = export_onnx(agent, folder / "fins.onnx", actuator="fins")
    slow, _, _ = export_onnx(
        agent, folder / "slow.onnx", actuator="realistic", actuator_params={"rpm_max": 1400.0}
    )
    return fins, slow


@pytest.mark.rl
def test_an_export_for_the_fins_states_it_and_is_flown_there(exports_for_other_actuators):
    """Was: the contract's env did not name the fins, so a run from it flew the paper's
    actuator (0.036 m RMS reported where the fins give 0.285 m)."""
    import onnx

    from auv_gym.rollout import rollout

    fins, _ = exports_for_other_actuators
    raw = read_contract(fins).raw
    assert raw["actuator"] == raw["env_kwargs"]["actuator"] == "fins" and raw["allocated"]
    # K·δ_max = 6.15 kg/rad · π/6 rad; the paper vehicle's X_max, M_max, N_max
    assert raw["allocation"]["fin_gain_kg"] == pytest.approx(6.15 * np.pi / 6, rel=1e-12)
    assert raw["allocation"]["limits"] == [50.0, 10.0, 10.0]
    assert [s["name"] for s in raw["stages"]] == ["envelope_guard", "actuator_allocation"]
    props = {p.key: p.value for p in onnx.load(fins).metadata_props}
    assert json.loads(props["env_kwargs"])["actuator"] == "fins"
    assert json.loads(props["allocation"]) == raw["allocation"]
    env_id, env = policy_env(f"onnx:{fins}")
    assert (env_id, env["actuator"]) == ("AUVPath3DPreview-v0", "fins")
    policy = controllers.make("onnx", path=str(fins))
    trajectory = rollout(policy, 0, max_time=2.0)  # the env from the contract alone
    assert trajectory.metadata["env_kwargs"]["actuator"] == "fins"
    own = policy.env_kwargs
    with pytest.raises(ValueError, match=r"exported for actuator 'fins', the env has 'paper'"):
        controllers.make("onnx", path=str(fins), env={**own, "actuator": "paper"})
    with pytest.raises(ValueError, match=r"draws its actuator per episode \(actuator='random'\)"):
        controllers.make("onnx", path=str(fins), env={**own, "actuator": "random"})
    with pytest.raises(ValueError, match=r"fin gain K·δ_max 3\.22 kg .* vehicle gives 2\.641 kg"):
        controllers.make("onnx", path=str(fins), env={**own, "params": {"fin_max": 0.4294}})


def _generalist_allocating(folder: Path, **settings: Any) -> Path:
    """A copy of the shipped generalist whose allocation stage has exactly ``settings`` (none:
    the bare allocation), whatever settings the shipped one carries."""
    shutil.copytree(AGENTS_DIR / "ppo_generalist", folder)
    for name in ("policy.onnx", "policy.json"):
        (folder / name).unlink()
    meta_file = folder / "metadata.json"
    meta = json.loads(meta_file.read_text())
    meta["stages"] = [
        {"name": "actuator_allocation", "commands": "paper", **settings}
        if stage["name"] == "actuator_allocation"
        else stage
        for stage in meta["stages"]
    ]
    meta_file.write_text(json.dumps(meta))
    return folder


def _allocation_exports(tmp_path: Path, variants: dict[str, dict[str, Any]]) -> dict:
    """{(label, actuator): the exported policy} of the generalist with each variant's allocation
    settings, exported for the fins and the paper's actuator (each passing its parity check);
    the files are ``<label>_<actuator>.onnx`` in ``tmp_path``."""
    from controllers.onnx_export import export_onnx

    exports = {}
    for label, settings in variants.items():
        agent = _generalist_allocating(tmp_path / label, **settings)
        for actuator in ("fins", "paper"):
            onnx_file = tmp_path / f"{label}_{actuator}.onnx"
            _, _, parity = export_onnx(agent, onnx_file, actuator=actuator)
            assert parity["max_abs_error"] <= 1e-5
            exports[label, actuator] = controllers.make("onnx", path=str(onnx_file))
    return exports


@pytest.mark.rl
def test_an_export_carries_the_observation_factors_on_the_fins_only(tmp_path):
    """The generalist with `observation_factors` on its allocation: exported for the fins its
    graph flies like the agent (the export's own parity check) and differs from the export
    without them; for the paper's actuator the factors go with the allocation (the same
    commands as without them)."""
    factors = {"x_e": 0.125, "y_e": 0.25, "z_e": 0.25}
    exports = _allocation_exports(
        tmp_path, {"plain": {}, "factored": {"observation_factors": factors}}
    )
    contract = read_contract(tmp_path / "factored_fins.onnx").raw
    assert contract["stages"][-1]["observation_factors"] == factors
    rng = np.random.default_rng(0)
    obs = np.zeros((64, len(NAMES)), np.float32)
    obs[:, NAMES.index("u")] = rng.uniform(0.8, 1.8, 64)  # flow over the fins
    for name in ("x_e", "y_e", "z_e"):
        obs[:, NAMES.index(name)] = rng.uniform(-1.0, 1.0, 64)  # [m]
    start = np.ones(64, dtype=bool)
    commands = {key: policy.predict(obs, episode_start=start)[0] for key, policy in exports.items()}
    np.testing.assert_array_equal(commands["factored", "paper"], commands["plain", "paper"])
    difference = np.abs(commands["factored", "fins"] - commands["plain", "fins"])
    assert difference.max() > 0.05  # the fins' errors seen at 1/8 and 1/4: other commands
    # the factored fins export is the plain one fed the scaled errors
    scaled = obs.copy()
    for name, factor in factors.items():
        scaled[:, NAMES.index(name)] *= factor
    plain_scaled, _ = exports["plain", "fins"].predict(scaled, episode_start=start)
    np.testing.assert_allclose(commands["factored", "fins"], plain_scaled, atol=1e-6)


@pytest.mark.rl
def test_an_export_for_the_fins_carries_the_allocations_surge_floor(tmp_path):
    """The generalist with a surge floor on its allocation (1.2 / 0.9 m/s): its export for the
    fins flies like the agent (the export's parity check), lists the floor in the guard it
    applies, and commands full ahead below 0.9 m/s; its export for the paper's actuator gives
    the commands of the export without the floor."""
    floor = {"surge_floor_soft": 1.2, "surge_floor_hard": 0.9}
    exports = _allocation_exports(tmp_path, {"plain": {}, "floored": floor})
    guard, allocation = read_contract(tmp_path / "floored_fins.onnx").raw["stages"]
    assert (guard["surge_floor_soft"], guard["surge_floor_hard"]) == (1.2, 0.9)
    assert allocation == {"name": "actuator_allocation", "commands": "paper", **floor}
    paper_stages = read_contract(tmp_path / "floored_paper.onnx").raw["stages"]
    assert [s["name"] for s in paper_stages] == ["envelope_guard"]
    assert "surge_floor_soft" not in paper_stages[0]
    rng = np.random.default_rng(1)
    obs = rng.normal(0.0, 1.0, (64, len(NAMES))).astype(np.float32)  # states of every kind
    obs[:, NAMES.index("u")] = rng.uniform(0.0, 0.9, 64)  # below the hard floor [m/s]
    start = np.ones(64, dtype=bool)
    commands = {key: policy.predict(obs, episode_start=start)[0] for key, policy in exports.items()}
    np.testing.assert_array_equal(commands["floored", "paper"], commands["plain", "paper"])
    assert np.mean(commands["plain", "fins"][:, 0] < 0.9) > 0.25  # the network would brake
    np.testing.assert_allclose(commands["floored", "fins"][:, 0], 1.0, atol=1e-6)  # full ahead
    np.testing.assert_array_equal(
        commands["floored", "fins"][:, 1:], commands["plain", "fins"][:, 1:]
    )


@pytest.mark.rl
def test_an_export_for_other_actuator_settings_states_them(exports_for_other_actuators):
    """Was: --actuator-params changed the graph but were not recorded, so the export was
    accepted beside other settings (commands up to 2 apart)."""
    _, slow = exports_for_other_actuators
    raw = read_contract(slow).raw
    assert raw["actuator_params"] == raw["env_kwargs"]["actuator_params"] == {"rpm_max": 1400.0}
    own = controllers.make("onnx", path=str(slow)).env_kwargs
    assert own["actuator"] == "realistic"
    default = {**own, "actuator_params": None}
    with pytest.raises(ValueError, match=r"differ in \['rpm_max'\]\): auv-gym export AGENT "):
        controllers.make("onnx", path=str(slow), env=default)
    # the servo rate limit is not in the allocation: the same graph flies it
    slower_fins = {**own, "actuator_params": {"rpm_max": 1400.0, "fin_rate_max": 0.9}}
    policy = controllers.make("onnx", path=str(slow), env=slower_fins)
    action, _ = policy.predict(np.zeros((2, 49), np.float32))
    assert action.shape == (2, 3)


def test_a_training_file_in_a_scratch_folder_is_not_provenance(tmp_path, monkeypatch):
    """Was: an agent trained under runs/ exported its run's phase config as ``config_file``,
    a path no other checkout has."""
    from controllers import onnx_export

    monkeypatch.setattr(onnx_export, "_REPOSITORY", tmp_path)
    for folder in ("runs/x", "out", "recipes"):
        (tmp_path / folder).mkdir(parents=True, exist_ok=True)
        (tmp_path / folder / "a.yml").write_text("a: 1\n")
    assert not onnx_export._repository_file("runs/x/a.yml")
    assert not onnx_export._repository_file("out/a.yml")
    assert onnx_export._repository_file("recipes/a.yml")
    assert not onnx_export._repository_file("recipes/missing.yml")


def test_a_residual_export_without_an_env_flies_the_env_it_carries():
    """Was: `controllers.make("onnx", path=...)` of `ppo_residual_as_built` built its base PID
    for the paper's actuator, which the climb-speed law refuses; the Python agent, loaded the
    same way, flies its own (propeller and fins)."""
    from auv_gym.rollout import evaluate

    folder = AGENTS_DIR / "ppo_residual_as_built"
    exported = controllers.make("onnx", path=str(folder / "policy.onnx"))
    python = controllers.make("agent", path=str(folder))
    assert exported.env_kwargs["actuator"] == python.env_kwargs["actuator"] == "realistic"
    a = evaluate(python, [0], max_time=60.0, transient=30.0)
    b = evaluate(exported, [0], max_time=60.0, transient=30.0)
    assert a[0]["rms_distance"] < 1.0
    assert b[0]["rms_distance"] == pytest.approx(a[0]["rms_distance"], rel=1e-3)
    paper = {"actuator": "paper", "observation": "preview_integral"}
    with pytest.raises(ValueError, match="the env has actuator 'paper': fly it with actuator="):
        controllers.make("onnx", path=str(folder / "policy.onnx"), env=paper)
