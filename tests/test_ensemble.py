"""Ensembles of saved agents (`controllers.ensemble`, `auv-gym ensemble`): the folder flies its
members' mean action, plain or residual; every member is checked and must fly like the others but
for its network; damaged lists, missing or nested members are one-line errors naming the file;
`--results --best K` takes the K best seeds by validation; an ensemble exports to one ONNX graph."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest

from benchmarks.training.residual import ResidualTraining
from controllers.agent import check_agent, observation_layout
from controllers.ensemble import ENSEMBLE_FILE, EnsembleActor, ensemble_members, write_ensemble

pytestmark = pytest.mark.rl

ENV = {"disturbance": "paper", "max_time": 4.0}


@pytest.fixture
def paper_agents(tmp_path, tiny_paper_model):
    """Two untrained 16-16 PPO agents on the paper's observation, training seeds 0 and 1."""
    from auv_gym.sim.observation import OBS_NAMES
    from benchmarks.training.checkpoints import save_agent

    folders = []
    for seed in (0, 1):
        model, venv = tiny_paper_model(seed)
        folder = tmp_path / "results" / f"agent_seed_{seed}"
        save_agent(
            model,
            venv,
            folder,
            {"obs_names": list(OBS_NAMES), "seed": seed, "env_id": "AUVPath3D-v0"},
        )
        folders.append(folder)
    return folders


def _observations(n: int = 16, dim: int = 15) -> np.ndarray:
    return np.random.default_rng(3).normal(0.0, 1.0, (n, dim)).astype(np.float32)


def test_an_ensemble_flies_the_mean_of_its_members_actions(tmp_path, paper_agents):
    from controllers.loader import load_policy

    folder = tmp_path / "ensemble"
    write_ensemble(folder, paper_agents)
    listed = json.loads((folder / ENSEMBLE_FILE).read_text())["members"]
    assert listed == ["../results/agent_seed_0", "../results/agent_seed_1"]  # moves with them
    files = check_agent(folder)
    assert [m.metadata["seed"] for m in files.members] == [0, 1]
    assert files.ensemble == folder / ENSEMBLE_FILE

    obs = _observations()
    a0, _ = load_policy(paper_agents[0]).predict(obs)
    a1, _ = load_policy(paper_agents[1]).predict(obs)
    ensemble = load_policy(folder)
    assert isinstance(ensemble, EnsembleActor)
    action, _ = ensemble.predict(obs)
    assert action.shape == (16, 3) and action.dtype == np.float32
    np.testing.assert_allclose(action, 0.5 * (a0 + a1), rtol=0, atol=1e-7)
    assert np.abs(a0 - a1).max() > 1e-3  # two networks: the mean is neither
    single, _ = ensemble.predict(obs[0])  # one row: torch's rounding of a batch of one
    np.testing.assert_allclose(single, action[0], rtol=0, atol=1e-7)


def test_a_residual_ensemble_keeps_its_base_and_averages_the_corrections(
    tmp_path, save_tiny_residual_agent
):
    from controllers.loader import load_policy
    from controllers.residual import ResidualPolicy

    settings = ResidualTraining(bound=(0.2, 0.4, 0.4))
    members = [tmp_path / f"agent_{seed}" for seed in (1, 2)]
    for seed, folder in zip((1, 2), members, strict=True):
        save_tiny_residual_agent(settings, folder, seed, ENV)
    write_ensemble(tmp_path / "ensemble", members)
    policy = load_policy(tmp_path / "ensemble")
    assert isinstance(policy, ResidualPolicy) and isinstance(policy.agent, EnsembleActor)

    features = np.random.default_rng(0).normal(0, 1, (8, policy.agent.obs_dim))
    c0, _ = load_policy(members[0]).agent.predict(features)
    c1, _ = load_policy(members[1]).agent.predict(features)
    mean, _ = policy.agent.predict(features)
    np.testing.assert_allclose(mean, 0.5 * (c0 + c1), rtol=0, atol=1e-7)

    obs = _observations(8)
    obs[:, :3] *= 0.3  # errors of a few tenths of a metre: the base does not saturate
    applied, _ = policy.predict(obs)
    base, _ = policy.base.predict(obs)
    # the correction is bounded by β = (0.2, 0.4, 0.4) about the base
    assert np.all(np.abs(applied - base) <= np.array([0.2, 0.4, 0.4]) + 1e-6)
    assert np.all(np.isfinite(applied))


def test_members_must_fly_alike_and_the_list_must_be_sound(
    tmp_path, paper_agents, save_tiny_residual_agent
):
    folder = tmp_path / "ensemble"
    folder.mkdir()
    spec = folder / ENSEMBLE_FILE

    def listing(*members) -> None:
        spec.write_text(json.dumps({"members": [str(m) for m in members]}))

    spec.write_text("{not json")
    with pytest.raises(ValueError, match=r"^ensemble .*ensemble.json is unreadable"):
        check_agent(folder)
    spec.write_text(json.dumps({"members": [str(paper_agents[0])], "weights": [1]}))
    with pytest.raises(ValueError, match="one key, 'members'"):
        check_agent(folder)
    listing(paper_agents[0])
    with pytest.raises(ValueError, match=r"lists 1 member\(s\); an ensemble needs 2 or more"):
        check_agent(folder)
    listing(paper_agents[0], paper_agents[0])
    with pytest.raises(ValueError, match=r"agent_seed_0.* more than once"):
        check_agent(folder)
    listing(paper_agents[0], paper_agents[0] / "model.zip")  # one agent by two paths
    with pytest.raises(ValueError, match=r"agent_seed_0' and '.*agent_seed_0/model.zip' are one"):
        check_agent(folder)
    (tmp_path / "README.md").write_text("not an agent")
    listing(paper_agents[0], tmp_path / "README.md")
    with pytest.raises(ValueError, match=r"README.md' is neither an agent folder nor a model zip"):
        check_agent(folder)
    listing(paper_agents[0], tmp_path / "missing")
    with pytest.raises(FileNotFoundError, match=r"member .*missing.* does not exist"):
        check_agent(folder)
    write_ensemble(tmp_path / "inner", paper_agents)
    listing(paper_agents[0], tmp_path / "inner")
    with pytest.raises(ValueError, match=r"member .*inner.* is an ensemble itself"):
        check_agent(folder)

    residual = tmp_path / "residual"
    save_tiny_residual_agent(ResidualTraining(), residual, 0, ENV)
    listing(paper_agents[0], residual)
    # the message shows where the layouts part, not their shared head
    differs = (
        r"member .*residual differs from .* in its observation layout \((\d+) entries vs (\d+), "
        r"first difference at entry (\d+): (.+) vs (.+)\)$"
    )
    with pytest.raises(ValueError, match=differs) as refused:
        check_agent(folder)
    theirs, ours, k, theirs_k, ours_k = re.search(differs, str(refused.value)).groups()
    k = int(k)
    residual_layout = observation_layout(check_agent(residual).metadata)
    paper_layout = observation_layout(check_agent(paper_agents[0]).metadata)
    assert (int(theirs), int(ours)) == (len(residual_layout), len(paper_layout))
    assert residual_layout[:k] == paper_layout[:k]
    named = [repr(v[k]) if k < len(v) else "no entry" for v in (residual_layout, paper_layout)]
    assert [theirs_k, ours_k] == named and named[0] != named[1]
    # a damaged member is named by its own file
    broken = shutil.copytree(paper_agents[1], tmp_path / "broken")
    (broken / "model.zip").write_bytes(b"not a zip")
    listing(paper_agents[0], broken)
    with pytest.raises(ValueError, match=r"^PPO model .*broken/model.zip is not a valid zip"):
        check_agent(folder)
    assert ensemble_members(tmp_path) is None  # a folder without the file is not an ensemble


def test_the_command_takes_the_best_seeds_by_validation_and_writes_nothing_wrong(
    tmp_path, paper_agents, auv_gym_command
):
    from benchmarks.runner.ensemble import best_seeds, main

    results = paper_agents[0].parent
    shutil.copytree(paper_agents[0], results / "agent_seed_2")
    metadata = json.loads((results / "agent_seed_2" / "metadata.json").read_text())
    (results / "agent_seed_2" / "metadata.json").write_text(json.dumps({**metadata, "seed": 2}))
    scores = {0: [0, 0.31], 1: [1, 0.20], 2: [0, 0.29]}  # seed 1 ended an episode early
    summary = {  # as train-seeds writes it: the score beside the summary it was taken from
        "seeds": [
            {"seed": s, "validation_score": v, "validation_summary": {"n_terminated": v[0]}}
            for s, v in scores.items()
        ]
    }
    (results / "summary.json").write_text(json.dumps(summary))
    assert best_seeds(results, 2) == [2, 0]
    assert best_seeds(results, 3) == [2, 0, 1]

    out = tmp_path / "best2"
    written = main(["--results", str(results), "--best", "2", "--out", str(out)])
    assert [m.rsplit("/", 1)[1] for m in written["members"]] == ["agent_seed_2", "agent_seed_0"]
    assert [m.metadata["seed"] for m in check_agent(out).members] == [2, 0]

    code, err = auv_gym_command("ensemble", "--results", str(results), "--best", "4", "--out", "x")
    assert code == 2 and err.endswith("summary.json lists 3 seeds")
    code, err = auv_gym_command("ensemble", "--out", str(tmp_path / "one"), str(paper_agents[0]))
    assert code == 2 and err.endswith("an ensemble needs 2 or more members")
    assert not (tmp_path / "one").exists()

    # a folder holding an export of another list is not rewritten under it; the same list is
    (out / "policy.onnx").write_bytes(b"graph of seeds 2 and 0")
    assert main(["--results", str(results), "--best", "2", "--out", str(out)]) == written
    code, err = auv_gym_command("ensemble", "--results", str(results), "--best", "3", "--out", out)
    assert code == 2 and err.endswith(
        f"--out {out} holds an export (policy.onnx) of another member list, which this list "
        "would leave beside it: choose a new folder, or remove the export first"
    )
    assert [m.metadata["seed"] for m in check_agent(out).members] == [2, 0]
    (tmp_path / "a_file").write_text("")
    code, err = auv_gym_command("ensemble", "--out", tmp_path / "a_file", *paper_agents)
    assert code == 2 and err.endswith(
        f"--out {tmp_path / 'a_file'} is a file; an ensemble is a folder"
    )
    (results / "summary.json").write_text('{"seeds": [')
    code, err = auv_gym_command("ensemble", "--results", results, "--best", "2", "--out", "x")
    assert code == 2 and f"--results: {results / 'summary.json'} is unreadable (" in err


def test_a_schedules_results_rank_by_what_the_schedule_selected_on(tmp_path, paper_agents):
    """Was: a schedule's results folder (schedule.json, no summary.json) was refused."""
    from benchmarks.runner.ensemble import best_seeds

    results = paper_agents[0].parent
    shutil.copytree(paper_agents[0], results / "agent_seed_2")

    def entry(seed, score):
        return {"seed": seed, "validation_score": [0, score], "validation_summary": {"n": 2}}

    last_phase = {"seeds": [entry(0, 0.30), entry(1, 0.20), entry(2, 0.25)]}
    schedule = {"plan": {}, "phases": [{"name": "base", "summary": last_phase}]}
    (results / "schedule.json").write_text(json.dumps(schedule))
    assert best_seeds(results, 2) == [1, 2]  # the last phase's validation
    shipped = {
        str(e["seed"]): {"score": [0, 1 - e["validation_score"][1]], "summary": {"n": 2}}
        for e in last_phase["seeds"]
    }
    (results / "schedule.json").write_text(
        json.dumps({**schedule, "shipped_selection": {"seeds": shipped}})
    )
    assert best_seeds(results, 3) == [0, 2, 1]  # select_on: shipped ranks the agents as shipped


def test_unlike_members_leave_no_ensemble(tmp_path, paper_agents, save_tiny_residual_agent):
    from benchmarks.runner.ensemble import main

    residual = tmp_path / "residual"
    save_tiny_residual_agent(ResidualTraining(), residual, 0, ENV)
    out = tmp_path / "mixed"
    with pytest.raises(SystemExit) as exit_info:
        main(["--out", str(out), str(paper_agents[0]), str(residual)])
    assert exit_info.value.code == 2
    assert not (out / ENSEMBLE_FILE).exists()


def test_an_ensemble_exports_to_one_graph_that_flies_its_mean(tmp_path, paper_agents):
    """One ONNX graph holds every member's normalisation and network and averages their
    actions: its commands equal the Python ensemble's, not either member's."""
    pytest.importorskip("onnx")
    pytest.importorskip("onnxruntime")
    from controllers.loader import load_policy
    from controllers.onnx_export import export_onnx
    from controllers.onnx_policy import inference_session

    write_ensemble(tmp_path / "pair", paper_agents)
    onnx_file, contract_file, parity = export_onnx(tmp_path / "pair", tmp_path / "pair.onnx")
    assert parity["max_abs_error"] <= 1e-5
    provenance = json.loads(contract_file.read_text())["provenance"]
    assert provenance["agent"] == "pair"
    assert [m["agent"] for m in provenance["members"]] == ["agent_seed_0", "agent_seed_1"]
    assert [m["seed"] for m in provenance["members"]] == [0, 1]
    assert all("model_sha256" in m and "exported_with" not in m for m in provenance["members"])

    obs = _observations(64)
    session = inference_session(onnx_file.read_bytes(), where=onnx_file)
    (got,) = session.run(None, {"observation": obs})
    want, _ = load_policy(tmp_path / "pair").predict(obs)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)
    a0, _ = load_policy(paper_agents[0]).predict(obs)
    assert np.abs(got - a0).max() > 1e-3  # the mean, not the first member


def test_a_residual_ensembles_export_flies_like_the_ensemble(tmp_path, save_tiny_residual_agent):
    """The residual ensemble's graph (mean correction, then bound and filter on the base's
    command) flown in closed loop by the ONNX runtime beside its base: the same episode."""
    pytest.importorskip("onnx")
    pytest.importorskip("onnxruntime")
    import controllers
    from auv_gym.rollout import evaluate
    from controllers.onnx_export import export_onnx

    settings = ResidualTraining(bound=(0.2, 0.4, 0.4))
    members = [tmp_path / f"agent_{seed}" for seed in (1, 2)]
    for seed, folder in zip((1, 2), members, strict=True):
        save_tiny_residual_agent(settings, folder, seed, ENV)
    write_ensemble(tmp_path / "ensemble", members)
    _, _, parity = export_onnx(tmp_path / "ensemble", tmp_path / "ensemble.onnx")
    assert parity["max_abs_error"] <= 1e-5

    env = {**ENV, "max_time": 20.0}
    python = controllers.make("agent", env=env, path=str(tmp_path / "ensemble"))
    exported = controllers.make("onnx", env=env, path=str(tmp_path / "ensemble.onnx"))
    (a,) = evaluate(python, [0], transient=5.0, **env)
    (b,) = evaluate(exported, [0], transient=5.0, **env)
    assert np.isfinite(a["rms_distance"]) and a["rms_distance"] > 0.0
    assert b["rms_distance"] == pytest.approx(a["rms_distance"], rel=1e-4)


def test_the_suite_flies_an_ensemble_as_one_run_and_its_digest_follows_the_members(
    tmp_path, paper_agents
):
    from benchmarks.runner.jobs import agent_digest
    from benchmarks.runner.suite_chunks import resolve_policy

    folder = tmp_path / "ensemble"
    write_ensemble(folder, paper_agents)
    policy = resolve_policy(f"pair={folder}")
    assert policy.kind == "agent" and len(policy.runs) == 1
    assert policy.runs[0].spec == f"agent:{folder}" and policy.runs[0].run == 0
    before = agent_digest(folder)
    stats = paper_agents[1] / "vecnormalize.npz"
    data = dict(np.load(stats))
    data["mean"] = data["mean"] + 1.0
    np.savez(stats, **data)
    assert agent_digest(folder) != before  # a changed member is a changed ensemble


def test_validation_scores_rank_agents_as_selection_does(tmp_path, paper_agents):
    """`benchmarks.analysis.validation_score`: the rule's score on a validation set's first
    seeds, per agent and for an ensemble of them; test sets are refused."""
    from benchmarks.analysis.validation_score import main, validation_score
    from benchmarks.training.evaluation import score

    write_ensemble(tmp_path / "pair", paper_agents)
    agents = [*paper_agents, tmp_path / "pair"]
    record = main(
        [
            "--agents",
            ",".join(map(str, agents)),
            "--task-set",
            "validation",
            "--episodes",
            "2",
            "--duration",
            "20",
            "--out",
            str(tmp_path / "scores"),
        ]
    )
    entries = record["agents"]
    assert [e["summary"]["n_episodes"] for e in entries] == [2, 2, 2]
    for entry in entries:  # the default rule on the summary, no chattering weight
        assert entry["score"] == list(score(entry["summary"]))
        assert entry["score"][1] > 0.0
    assert record["lowest"] == min(entries, key=lambda e: tuple(e["score"]))["agent"]
    assert json.loads((tmp_path / "scores" / "validation_score.json").read_text()) == record
    with pytest.raises(ValueError, match="is a test set, not a validation set"):
        validation_score(paper_agents[0], "test_distribution", 2, 20.0)


def test_an_ensemble_with_the_mirror_guard_and_allocation_exports_for_the_fins(tmp_path):
    """Two members with every stage a plain agent can list (the generalist's guard and
    allocation, plus the mirror; the second member's normalisation shifted, so the two fly
    differently): the graph mirrors each member's network, averages, then guards and allocates
    once for the fins, and the export's parity check holds it to the Python ensemble."""
    pytest.importorskip("onnx")
    from benchmarks.catalog.policies import AGENTS_DIR
    from controllers.loader import load_policy
    from controllers.mirror import MirroredNetwork
    from controllers.onnx_export import export_onnx

    members = [tmp_path / "first", tmp_path / "second"]
    for folder in members:
        shutil.copytree(AGENTS_DIR / "ppo_generalist", folder)
        meta = json.loads((folder / "metadata.json").read_text())
        meta["stages"] = [*meta["stages"], {"name": "mirror_symmetry"}]
        (folder / "metadata.json").write_text(json.dumps(meta))
    stats = dict(np.load(members[1] / "vecnormalize.npz"))
    stats["mean"] = stats["mean"] + 0.3 * np.sqrt(stats["var"])
    np.savez(members[1] / "vecnormalize.npz", **stats)
    write_ensemble(tmp_path / "pair", members)

    policy = load_policy(tmp_path / "pair")
    assert isinstance(policy.actor, MirroredNetwork)
    assert isinstance(policy.actor.network, EnsembleActor)
    _, contract, parity = export_onnx(tmp_path / "pair", tmp_path / "pair.onnx", actuator="fins")
    _, _, alone = export_onnx(members[0], tmp_path / "first.onnx", actuator="fins")
    assert parity["max_abs_error"] <= 1e-5 and alone["max_abs_error"] <= 1e-5
    raw = json.loads(contract.read_text())
    assert [s["name"] for s in raw["stages"]] == [
        "mirror_symmetry",
        "envelope_guard",
        "actuator_allocation",
    ]
    assert raw["actuator"] == "fins" and len(raw["provenance"]["members"]) == 2
    assert (tmp_path / "pair.onnx").stat().st_size > 1.8 * (tmp_path / "first.onnx").stat().st_size
