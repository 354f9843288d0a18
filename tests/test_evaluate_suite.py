"""The test-suite evaluation (`benchmarks.runner.evaluate_suite`) and its statistics
(`benchmarks.analysis.suite_stats`) on a tiny suite: 2 sets × 2 seeds, 10-s episodes, FBSM and a
fake 2-seed agent directory made of the shipped agent."""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

import benchmarks.runner.evaluate_suite as suite_module
import benchmarks.runner.suite_chunks as chunks_module
from auv_gym.sim.trajectory import FAILURE_REASONS
from benchmarks.analysis.suite_stats import write_stats
from benchmarks.catalog.policies import AGENTS_DIR, check_policy_spec
from benchmarks.catalog.scenarios import load_scenarios
from benchmarks.reports.table_format import format_number
from benchmarks.runner.evaluate_suite import main
from benchmarks.runner.jobs import Job, run_job

TASKS = """
[train]
role = "train"
seeds = { first = 1000, count = 1000 }
env.path = { families = ["helix", "line"], radius = [15.0, 40.0], climb_angle_deg = [0.0, 20.0] }

[test_mixed]
role = "test"
seeds = { first = 0, count = 2 }
env.disturbance = "paper"
env.path = { families = ["helix", "line"], radius = [15.0, 40.0], climb_angle_deg = [0.0, 20.0] }

[test_fins]
role = "test"
seeds = { first = 3, count = 2 }
scenarios = ["fins"]
"""
DURATION = "10"
REPS = "200"


def make_multi_seed(
    folder: Path, seeds=(3, 5), env_ids=("AUVPath3D-v0", "AUVPath3DSpeedLimit-v0")
) -> Path:
    """A multi-seed results directory (layout of `benchmarks.training.seeds_cli --results`): the
    shipped agent per seed, metadata with that seed and env id, and a learning curve per seed."""
    folder.mkdir(parents=True)
    for k, (seed, env_id) in enumerate(zip(seeds, env_ids, strict=True)):
        agent = folder / f"agent_seed_{seed}"
        shutil.copytree(AGENTS_DIR / "ppo_generalist", agent)
        meta = json.loads((agent / "metadata.json").read_text())
        (agent / "metadata.json").write_text(json.dumps({**meta, "seed": seed, "env_id": env_id}))
        rows = [(0, 0.0, 5.0), (1000, 10.0 + k, 2.0 + k), (2000, 20.0 + k, 1.0 + k)]
        (folder / f"seed_{seed}_learning_curve.csv").write_text(
            "num_timesteps,wall_time_s,rms_distance_mean,rms_distance_std,rms_distance_max,"
            "n_terminated,max_surge_max\n"
            + "".join(f"{n},{t},{r},0,{r},0,1.5\n" for n, t, r in rows)
        )
    return folder


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The tiny suite evaluated once (one process): its folder, arguments and tasks file."""
    root = tmp_path_factory.mktemp("suite")
    tasks = root / "tasks.toml"
    tasks.write_text(TASKS)
    multi = make_multi_seed(root / "multi")
    out = root / "out"
    argv = [
        "--tasks-file",
        str(tasks),
        "--policies",
        f"fbsm,gen={multi}",
        "--duration",
        DURATION,
        "--workers",
        "1",
        "--out",
        str(out),
        "--reps",
        REPS,
        "--quiet",
    ]
    main(argv)
    return {"out": out, "argv": argv, "tasks": tasks, "multi": multi, "root": root}


def read_rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def test_rows_cover_every_policy_run_set_and_seed(tiny):
    rows = read_rows(tiny["out"] / "episodes.csv")
    keys = [(r["policy"], r["run"], r["set"], r["seed"]) for r in rows]
    assert len(rows) == 12 and len(set(keys)) == 12  # fbsm 1 run + gen 2 runs, × 2 sets × 2 seeds
    assert {k[:2] for k in keys} == {("fbsm", "0"), ("gen", "3"), ("gen", "5")}
    assert {(k[2], k[3]) for k in keys} == {
        ("test_mixed", "0"),
        ("test_mixed", "1"),
        ("scenario:fins", "3"),
        ("scenario:fins", "4"),
    }
    env_ids = {(r["policy"], r["run"]): r["env_id"] for r in rows}
    assert env_ids == {
        ("fbsm", "0"): "AUVPath3D-v0",
        ("gen", "3"): "AUVPath3D-v0",
        ("gen", "5"): "AUVPath3DSpeedLimit-v0",
    }
    for r in rows:
        assert float(r["duration"]) <= 10.0 and float(r["max_surge"]) > 0.5
        if r["termination_reason"] == "time_limit":
            assert int(r["window_samples"]) == 101  # t = 5.0, 5.05, ..., 10.0 s
            assert 0.0 < float(r["rms_distance"]) < 30.0
    # The surge limit of v1 (2.0 m/s) ends an episode exactly when the agent exceeds it.
    for r in rows:
        over = float(r["max_surge"]) > 2.0
        if r["env_id"] == "AUVPath3DSpeedLimit-v0":
            assert (r["termination_reason"] == "overspeed") == over
        else:
            assert r["termination_reason"] != "overspeed"
    suite = json.loads((tiny["out"] / "suite.json").read_text())
    assert suite["duration_s"] == 10.0 and suite["transient_s"] == 5.0
    assert "evaluate_suite" in suite["command"] and "numpy" in suite["versions"]
    assert suite["sets"]["scenario:fins"]["kind"] == "scenario"
    assert [r["run"] for r in suite["policies"]["gen"]["runs"]] == [3, 5]


def test_full_precision_and_the_same_episodes_as_compare(tiny, tmp_path):
    """A scenario set runs with the scenario's controller kwargs exactly as compare does: the
    FBSM row of scenario:fins equals compare's episode (fins actuator model) to the last bit."""
    rows = read_rows(tiny["out"] / "episodes.csv")
    mine = next(
        r
        for r in rows
        if r["policy"] == "fbsm" and r["set"] == "scenario:fins" and r["seed"] == "3"
    )
    job = Job("fbsm", load_scenarios()["fins"], 3, 10.0, 5.0)
    metrics = run_job(job, tmp_path)["metrics"]
    for column, key in suite_module.METRICS.items():
        expected = metrics.get(key, math.nan)  # max_roll: the 6-DOF plant's only
        assert mine[column] == (repr(expected) if isinstance(expected, float) else str(expected))


def test_resume_after_a_crash_reruns_only_unfinished_chunks(tiny, tmp_path, monkeypatch):
    out = tmp_path / "out"
    shutil.copytree(tiny["out"], out)
    argv = [*tiny["argv"][:-5], "--out", str(out), "--no-stats", "--quiet"]
    before = (out / "episodes.csv").read_bytes()
    chunk_files = sorted((out / "chunks").rglob("*.json"))
    assert len(chunk_files) == 6  # (fbsm, gen 3, gen 5) × 2 sets
    lost = out / "chunks" / "gen" / "run_5" / "test_mixed.json"
    lost.unlink()
    (out / "episodes.csv").unlink()
    (lost.parent / ".test_mixed.json.auv-gym.k1ll3d00.tmp").write_text("{")  # a killed write
    stamps = {p: p.stat().st_mtime_ns for p in chunk_files if p != lost}
    calls = []
    real = chunks_module.evaluate

    def counting(policy, seeds, **kwargs):
        calls.append(list(seeds))
        return real(policy, seeds, **kwargs)

    monkeypatch.setattr(chunks_module, "evaluate", counting)
    main(argv)
    assert calls == [[0, 1]]  # only the lost chunk is simulated again
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items())
    assert not list(out.rglob(".*.tmp"))
    assert (out / "episodes.csv").read_bytes() == before  # bit-identical
    calls.clear()
    main(argv)  # everything finished: nothing runs
    assert calls == []


def test_chunks_copied_under_a_new_label_are_reused_and_carry_it(tiny, tmp_path, monkeypatch):
    """The fingerprint leaves the label out: the agent's episodes, filed under another name, are
    not flown again, and every row names the policy as this command calls it."""
    out = tmp_path / "out"
    (out / "chunks").mkdir(parents=True)
    shutil.copytree(tiny["out"] / "chunks" / "gen", out / "chunks" / "renamed")
    shutil.copytree(tiny["out"] / "chunks" / "fbsm", out / "chunks" / "fbsm")
    argv = [*tiny["argv"][:-5], "--out", str(out), "--no-stats", "--quiet"]
    argv[argv.index("--policies") + 1] = f"fbsm,renamed={tiny['multi']}"
    monkeypatch.setattr(chunks_module, "evaluate", lambda *a, **k: pytest.fail("simulated"))
    main(argv)
    rows = read_rows(out / "episodes.csv")
    before = read_rows(tiny["out"] / "episodes.csv")
    assert {r["policy"] for r in rows} == {"fbsm", "renamed"}
    assert [{**r, "policy": r["policy"].replace("renamed", "gen")} for r in rows] == before


def test_a_chunk_stored_before_a_metric_existed_is_reused_with_nan(tiny, tmp_path, monkeypatch):
    """A suite resumed across the release that added `mean_path_speed` (the pace, m/s): its
    stored chunks are not flown again, and their rows say NaN for it, not KeyError."""
    out = tmp_path / "out"
    shutil.copytree(tiny["out"], out)
    for chunk in (out / "chunks").rglob("*.json"):
        record = json.loads(chunk.read_text())
        for episode in record["episodes"]:
            del episode["mean_path_speed"]
        chunk.write_text(json.dumps(record))
    argv = [*tiny["argv"][:-5], "--out", str(out), "--no-stats", "--quiet"]
    monkeypatch.setattr(chunks_module, "evaluate", lambda *a, **k: pytest.fail("simulated"))
    main(argv)
    rows = read_rows(out / "episodes.csv")
    fresh = read_rows(tiny["out"] / "episodes.csv")
    assert {r["mean_path_speed"] for r in rows} == {"nan"}
    # u_p = u_D(1 + tanh(x_e/σ)) lies in [0, 2u_D], u_D = 1 m/s; a fresh row has its value
    paces = [float(r["mean_path_speed"]) for r in fresh if r["rms_distance"] != "nan"]
    assert paces and all(0.0 <= pace <= 2.0 for pace in paces)
    strip = [{k: v for k, v in r.items() if k != "mean_path_speed"} for r in rows]
    assert strip == [{k: v for k, v in r.items() if k != "mean_path_speed"} for r in fresh]


def test_a_crashed_run_keeps_its_finished_chunks(tiny, tmp_path, monkeypatch):
    out = tmp_path / "out"
    argv = [
        "--tasks-file",
        str(tiny["tasks"]),
        "--policies",
        "fbsm,backstepping",
        "--duration",
        DURATION,
        "--workers",
        "1",
        "--out",
        str(out),
        "--no-stats",
        "--quiet",
    ]
    real = chunks_module.evaluate
    calls = []

    def crash_on_third(policy, seeds, **kwargs):
        calls.append(list(seeds))
        if len(calls) == 3:
            raise KeyboardInterrupt  # as a Ctrl-C mid-run
        return real(policy, seeds, **kwargs)

    monkeypatch.setattr(chunks_module, "evaluate", crash_on_third)
    with pytest.raises(KeyboardInterrupt):
        main(argv)
    assert len(list((out / "chunks").rglob("*.json"))) == 2 and not (out / "episodes.csv").exists()
    calls.clear()
    monkeypatch.setattr(
        chunks_module, "evaluate", lambda p, s, **k: calls.append(s) or real(p, s, **k)
    )
    main(argv)
    assert len(calls) == 2  # 4 chunks, 2 kept
    assert len(read_rows(out / "episodes.csv")) == 8


@pytest.mark.integration
def test_rerun_with_two_workers_is_bit_identical(tiny, tmp_path):
    out = tmp_path / "again"
    argv = [*tiny["argv"][:-5], "--out", str(out), "--no-stats", "--quiet"]
    argv[argv.index("--workers") + 1] = "2"
    main(argv)
    assert (out / "episodes.csv").read_bytes() == (tiny["out"] / "episodes.csv").read_bytes()


def usage_error(capsys, argv: list[str]) -> str:
    with pytest.raises(SystemExit) as caught:
        main(argv)
    assert caught.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_bad_input_is_one_line_before_any_episode(tiny, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(chunks_module, "evaluate", lambda *a, **k: pytest.fail("simulated"))
    corrupt = tmp_path / "corrupt"
    shutil.copytree(tiny["multi"], corrupt)
    model = corrupt / "agent_seed_5" / "model.zip"
    model.write_bytes(model.read_bytes()[:1000])
    (tmp_path / "empty").mkdir()
    foreign = make_multi_seed(tmp_path / "foreign", seeds=(0,), env_ids=("CartPole-v1",))
    base = [
        "--tasks-file",
        str(tiny["tasks"]),
        "--duration",
        DURATION,
        "--out",
        str(tmp_path / "o"),
    ]
    cases = [
        (["--policies", "fbsm,lqr"], "unknown policy 'lqr'"),
        (["--policies", "fbsm", "--sets", "test_mixed,nope"], "unknown set ['nope']"),
        (["--policies", f"fbsm,g={tmp_path / 'missing'}"], "agent directory"),
        (["--policies", f"fbsm,g={tmp_path / 'empty'}"], "neither an agent (model.zip) nor"),
        (["--policies", f"fbsm,g={corrupt}"], "is not a valid zip file"),
        (["--policies", f"fbsm,g={foreign}"], "records env_id 'CartPole-v1'"),
        (["--policies", f"fbsm,a b={tiny['multi']}"], "NAME 'a b' must be letters"),
        (["--policies", "backstepping"], "--reference 'fbsm' is not among --policies"),
        (["--policies", "fbsm", "--duration", "0"], "--duration must be a finite number in (0"),
        (["--policies", "fbsm", "--workers", "0"], "--workers must be an integer in [1, 1024]"),
        (["--policies", "fbsm", "--reps", "10"], "--reps must be an integer in [100, 100000]"),
        (["--policies", "fbsm", "--stats-only"], "episodes.csv does not exist"),
        (["--policies", "fbsm", "--plant", "7dof"], "unknown --plant '7dof'; valid: ['5dof'"),
    ]
    for extra, message in cases:
        err = usage_error(capsys, [*base, *extra])
        assert message in err, (extra, err)
    assert not (tmp_path / "o").exists()
    err = usage_error(capsys, ["--tasks-file", str(tmp_path / "none.toml"), "--out", str(tmp_path)])
    assert f"task file {tmp_path / 'none.toml'}: cannot be read (No such file" in err
    (tmp_path / "broken.toml").write_text('[x]\nrole = "test"\nseeds = { first = 0,\n')
    err = usage_error(capsys, ["--tasks-file", str(tmp_path / "broken.toml"), "--out", "o"])
    assert f"task file {tmp_path / 'broken.toml'}: not valid TOML (" in err  # was: no file named


def test_former_policy_names_say_what_to_type(tmp_path, capsys):
    with pytest.raises(ValueError, match="policy 'ppo_cross_track_guard_alloc' was renamed: use "):
        check_policy_spec("ppo_cross_track_guard_alloc")
    for retired in ("ppo", "ppo_helix"):  # the helix specialist and its former name
        with pytest.raises(ValueError, match=f"policy '{retired}' is no longer shipped"):
            check_policy_spec(retired)
    with pytest.raises(ValueError, match=r"'ppo:PATH' was renamed, use 'agent:x'"):
        check_policy_spec("ppo:x")
    err = usage_error(capsys, ["--policies", "fbsm,sac_helix", "--out", str(tmp_path / "o")])
    assert "'sac_helix' is no longer shipped" in err and "ppo_generalist" in err
    assert not (tmp_path / "o").exists()


def test_statistics_of_the_tiny_suite(tiny, monkeypatch):
    out = tiny["out"]
    stats = json.loads((out / "stats.json").read_text())
    assert stats["scopes"] == ["test_mixed", "scenario:fins", "aggregate"]
    assert stats["n_runs"] == {"fbsm": 1, "gen": 2}
    for name in ("iqm", "mean"):
        for scope in stats["scopes"]:
            for policy in ("fbsm", "gen"):
                iv = stats[name][scope][policy]
                assert iv["low"] <= iv["value"] <= iv["high"], (name, scope, policy, iv)
    rows = read_rows(out / "episodes.csv")
    for t in stats["target"]:  # by hand from episodes.csv

        def mean(policy, t=t):
            values = [
                30.0 if r["termination_reason"] in FAILURE_REASONS else float(r["rms_distance"])
                for r in rows
                if r["policy"] == policy and r["set"] == t["set"]
            ]
            return sum(values) / len(values)

        assert t["policy"] == "gen" and t["episodes"] == 4
        assert math.isclose(t["ratio"], mean("gen") / mean("fbsm"), rel_tol=1e-12)
        surge = max(
            float(r["max_surge"]) for r in rows if r["policy"] == "gen" and r["set"] == t["set"]
        )
        assert t["max_surge_m_s"] == surge
        assert t["passed"] == (t["ratio"] <= 2 and t["failed"] == 0 and surge <= 2.0)
        assert t["ratio_low"] <= t["ratio"] <= t["ratio_high"]
    chattering = [float(r["chattering"]) for r in rows if r["policy"] == "fbsm"]
    aggregate = stats["chattering"]["aggregate"]
    assert aggregate["fbsm"]["value"] == pytest.approx(np.mean(chattering), rel=1e-12)
    assert aggregate["fbsm"]["ratio"] == 1.0 and 1.0 < aggregate["fbsm"]["value"] < 100.0
    assert stats["paired"] == {}  # no residual agent or low-pass baseline evaluated
    curves = stats["learning_curves"]["gen"]
    assert curves["env steps"]["x"] == [0.0, 1000.0, 2000.0]
    assert curves["env steps"]["iqm"] == [5.0, 2.5, 1.5]  # mean of two runs (IQM of 2 = mean)
    for name in (
        "intervals",
        "improvement_over_fbsm",
        "profile_aggregate",
        "learning_curves",
        "smoothness_tradeoff",
    ):
        assert (out / "figures" / f"{name}.png").stat().st_size > 10_000
    md = (out / "stats.md").read_text()
    assert "| scenario:fins | gen |" in md and "## IQM RMS distance [m]" in md
    fins = next(t for t in stats["target"] if t["set"] == "scenario:fins")
    assert "| ratio [95 % CI] |" in md
    assert f"| {format_number(fins['ratio'])} [{format_number(fins['ratio_low'])}, " in md
    # --stats-only: regenerated without simulating, bit-identical.
    before = (out / "stats.json").read_bytes()
    monkeypatch.setattr(chunks_module, "evaluate", lambda *a, **k: pytest.fail("simulated"))
    main(["--stats-only", "--out", str(out), "--reps", REPS, "--no-figures"])
    assert (out / "stats.json").read_bytes() == before


def test_paired_table_by_hand():
    from benchmarks.analysis.smoothness_stats import paired_table

    base = np.array([[0.10, 0.10, 0.20, 0.20]])
    scores = {
        "fbsm_colos": base,
        "ppo_residual": np.vstack([base - 0.01, base - 0.03]),
        "fbsm_colos_lowpass": base * 1.2,
    }
    pairs = [
        ("ppo_residual", "fbsm_colos"),
        ("ppo_residual_v2", "fbsm_colos"),
        ("fbsm_colos_lowpass", "fbsm_colos"),
        ("ppo_residual", "fbsm_colos_lowpass"),
    ]
    table = paired_table(
        scores, ["a", "a", "b", "b"], reps=200, seed=0, pairs=pairs, worse_ratio=0.1
    )
    assert list(table) == [
        "ppo_residual−fbsm_colos",
        "fbsm_colos_lowpass−fbsm_colos",
        "ppo_residual−fbsm_colos_lowpass",
    ]
    res = table["ppo_residual−fbsm_colos"]["aggregate"]
    assert res["difference"]["value"] == pytest.approx(-0.02) and res["win"] and not res["worse"]
    assert res["relative"]["value"] == pytest.approx(-0.02 / 0.15)
    low = table["fbsm_colos_lowpass−fbsm_colos"]["a"]
    assert low["relative"]["value"] == pytest.approx(0.2) and low["worse"] and not low["win"]


def test_chattering_ratios_only_against_a_reference_the_run_flew():
    """Was: a suite without fbsm headed its chattering table "ratio to fbsm" with a dash in
    every cell."""
    from benchmarks.analysis.smoothness_stats import chattering_table, smoothness_markdown

    chattering = {"pid": np.array([[1.0, 1.0, 3.0, 3.0]]), "agent": np.array([[0.5] * 4])}
    groups = ["a", "a", "b", "b"]
    with_ref = chattering_table(chattering, groups, reps=200, seed=0, reference="pid")
    assert with_ref["aggregate"]["agent"]["ratio"] == pytest.approx(0.25)
    text = smoothness_markdown({}, with_ref, "pid", 0.1)
    assert "## Chattering [1/s] (ratio to pid), 95 % CI" in text and "(0.250)" in text
    without = chattering_table(chattering, groups, reps=200, seed=0, reference="fbsm")
    text = smoothness_markdown({}, without, "fbsm", 0.1)
    assert (
        "## Chattering [1/s], 95 % CI (no ratios: fbsm, their reference, was not evaluated)" in text
    )
    assert "(—)" not in text and "ratio to" not in text
    assert "| aggregate | 2.00 [2.00, 2.00] | 0.500 [0.500, 0.500] |" in text


def test_target_table_by_hand(tmp_path):
    """Failures score the corridor (30 m); ratio = mean / reference mean; pass rules."""
    sets = {"a": {"env": {}, "kind": "distribution"}, "b": {"env": {"corridor": 20.0}}}
    suite = {
        "command": "by hand",
        "sets": sets,
        "policies": {"fbsm": {"results": None}, "x": {"results": None}},
    }
    (tmp_path / "suite.json").write_text(json.dumps(suite))
    header = (
        "policy,run,set,seed,env_id,rms_distance,rms_x_e,rms_y_e,rms_z_e,max_distance,"
        "max_surge,overspeed_fraction,termination_reason,window_samples,duration\n"
    )
    cells = [
        ("fbsm", 0, "a", 0, 0.1, 1.0, "time_limit"),
        ("fbsm", 0, "a", 1, 0.3, 1.0, "time_limit"),
        ("fbsm", 0, "b", 0, 0.2, 1.0, "time_limit"),
        ("fbsm", 0, "b", 1, 0.2, 1.0, "time_limit"),
        ("x", 1, "a", 0, 0.2, 1.9, "time_limit"),
        ("x", 1, "a", 1, 0.3, 1.2, "time_limit"),
        ("x", 2, "a", 0, 0.5, 1.1, "time_limit"),
        ("x", 2, "a", 1, 0.1, 1.0, "time_limit"),
        ("x", 1, "b", 0, 0.2, 1.0, "time_limit"),
        ("x", 1, "b", 1, 0.3, 2.5, "overspeed"),
        ("x", 2, "b", 0, 0.1, 1.0, "time_limit"),
        ("x", 2, "b", 1, 0.1, 1.0, "time_limit"),
    ]
    lines = [
        f"{p},{r},{s},{k},AUVPath3D-v0,{d},0,0,0,{d},{u},0,{end},10,10.0\n"
        for p, r, s, k, d, u, end in cells
    ]
    (tmp_path / "episodes.csv").write_text(header + "".join(lines))
    text = write_stats(tmp_path, reps=200, figures=False)
    stats = json.loads((tmp_path / "stats.json").read_text())
    a, b = stats["target"]
    assert (a["set"], b["set"]) == ("a", "b")
    assert math.isclose(a["mean_m"], 0.275) and math.isclose(a["reference_mean_m"], 0.2)
    assert math.isclose(a["ratio"], 1.375) and a["failed"] == 0 and a["max_surge_m_s"] == 1.9
    assert a["passed"]
    # Set b: the overspeed episode scores the set's corridor, 20 m.
    assert math.isclose(b["mean_m"], (0.2 + 20.0 + 0.1 + 0.1) / 4)
    assert math.isclose(b["ratio"], 20.4 / 4 / 0.2) and b["failed"] == 1
    assert b["failures"] == ["overspeed"] and not b["passed"]
    assert stats["verdicts"]["x"] == {"sets": 2, "passed": 1, "failing_sets": ["b"]}
    assert stats["failure_score_m"] == {"a": 30.0, "b": 20.0}
    b_ratio = f"25.5 [{format_number(b['ratio_low'])}, {format_number(b['ratio_high'])}]"
    assert f"| b | x | 5.10 | 0.200 | {b_ratio} | 1/4 (overspeed) | 2.50 | **FAIL** |" in text
    # Runs and episodes resampled: a quarter of the replicates draw run 2 twice (0.1 m on both
    # episodes, 0.5×); the worst draws run 1's 20-m episode alone (100×).
    assert b["ratio_low"] == 0.5 and 25.5 < b["ratio_high"] <= 100.0
    # IQM of set a for x: 4 scores [0.1, 0.2, 0.3, 0.5] → the middle two, 0.25.
    assert math.isclose(stats["iqm"]["a"]["x"]["value"], 0.25)
    # fbsm beats x in set a on 1 of 4 (run, episode) pairs per episode, ties ½:
    # episode 0: fbsm 0.1 vs x 0.2, 0.5 → x better on none; episode 1: 0.3 vs 0.3 (½), 0.1 (1).
    assert math.isclose(stats["improvement"]["fbsm"]["a"]["x"]["value"], (0 + 0.75) / 2)
    assert np.isfinite(stats["mean"]["aggregate"]["x"]["value"])


def test_stats_only_names_a_damaged_record_in_one_line(tmp_path, capsys):
    """Was: a cut-short episodes.csv ended in a TypeError traceback; a bad cell or suite.json
    gave a bare parser message naming no file."""
    suite = {"command": "by hand", "sets": {"a": {"env": {}}}, "policies": {"fbsm": {}}}
    header = (
        "policy,run,set,seed,env_id,rms_distance,rms_x_e,rms_y_e,rms_z_e,max_distance,"
        "max_surge,overspeed_fraction,termination_reason,window_samples,duration\n"
    )
    row = "fbsm,0,a,{seed},AUVPath3D-v0,{d},0,0,0,{d},1.0,0,time_limit,10,10.0\n"
    whole = header + row.format(seed=0, d=0.1) + row.format(seed=1, d=0.2)
    episodes = tmp_path / "episodes.csv"
    (tmp_path / "suite.json").write_text(json.dumps(suite))
    for text, message in (
        (whole[: len(whole) - 30], f"{episodes}: line 3 has another number of cells"),
        (whole.replace(",0.2,", ",abc,", 1), f"{episodes}: line 3: rms_distance = 'abc' is not"),
        (whole.replace(",0.2,", ",-1000,", 1), f"{episodes}: line 3: rms_distance = '-1000' is"),
        (header.replace("run,", "") + "fbsm,a\n", f"{episodes}: no column run (not an episodes"),
    ):
        episodes.write_text(text)
        err = usage_error(capsys, ["--stats-only", "--out", str(tmp_path)])
        assert message in err, (message, err)
    episodes.write_text(whole)
    (tmp_path / "suite.json").write_text("{broken")
    err = usage_error(capsys, ["--stats-only", "--out", str(tmp_path)])
    assert f"{tmp_path / 'suite.json'}: not a suite record (" in err
    assert not (tmp_path / "stats.md").exists()


def test_target_table_reports_each_side_pace(tmp_path):
    """The pace (mean virtual-point speed, m/s) of the policy and of the set's reference, a
    column of the table when the episodes recorded it; a file from before it has none."""
    suite = {
        "command": "by hand",
        "sets": {"a": {"env": {}, "kind": "distribution"}},
        "policies": {"fbsm": {"results": None}, "x": {"results": None}},
    }
    (tmp_path / "suite.json").write_text(json.dumps(suite))
    header = (
        "policy,run,set,seed,env_id,rms_distance,rms_x_e,rms_y_e,rms_z_e,max_distance,"
        "max_surge,overspeed_fraction,mean_path_speed,termination_reason,window_samples,duration\n"
    )
    cells = [("fbsm", 0, 0.2, 1.0), ("fbsm", 1, 0.2, 1.02), ("x", 0, 0.1, 1.2), ("x", 1, 0.1, 1.1)]
    lines = [
        f"{p},0,a,{k},AUVPath3D-v0,{d},0,0,0,{d},1.5,0,{pace},time_limit,10,10.0\n"
        for p, k, d, pace in cells
    ]
    (tmp_path / "episodes.csv").write_text(header + "".join(lines))
    text = write_stats(tmp_path, reps=200, figures=False)
    (row,) = json.loads((tmp_path / "stats.json").read_text())["target"]
    assert math.isclose(row["pace_m_s"], 1.15) and math.isclose(row["reference_pace_m_s"], 1.01)
    assert "pace [m/s], policy / reference" in text
    assert (
        "| a | x | 0.100 | 0.200 | 0.500 [0.500, 0.500] | 0/2 | 1.50 | 1.15 / 1.01 | pass |" in text
    )
    # the same episodes without the column: no pace, no column
    old = [",".join(c for i, c in enumerate(line.split(",")) if i != 12) for line in lines]
    (tmp_path / "episodes.csv").write_text(header.replace("mean_path_speed,", "") + "".join(old))
    text = write_stats(tmp_path, reps=200, figures=False)
    assert "pace" not in text
    assert "| a | x | 0.100 | 0.200 | 0.500 [0.500, 0.500] | 0/2 | 1.50 | pass |" in text


def test_a_rerun_without_statistics_removes_the_earlier_statistics(tiny, tmp_path):
    """Was: stats.json, stats.md and figures/ of the earlier run stayed beside the new
    episodes.csv they do not describe."""
    out = tmp_path / "out"
    shutil.copytree(tiny["out"], out)
    main(["--stats-only", "--out", str(out), "--reps", REPS])  # other tests rewrite tiny's
    assert (out / "stats.json").is_file() and any((out / "figures").iterdir())
    argv = [*tiny["argv"][:-4], str(out), "--no-stats", "--quiet"]
    assert argv[argv.index("--out") + 1] == str(out)
    main(argv)  # every chunk is cached: no episode runs
    assert not (out / "stats.json").exists() and not (out / "stats.md").exists()
    assert not (out / "figures").exists()
    assert (out / "episodes.csv").read_text() == (tiny["out"] / "episodes.csv").read_text()
