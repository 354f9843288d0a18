"""The benchmark CLI (`python -m benchmarks.runner.compare`) end to end on tiny grids."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from benchmarks.catalog.policies import check_policy_spec
from benchmarks.catalog.scenarios import load_scenarios, select
from benchmarks.runner.compare import main

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": f"{ROOT / 'tests'}{os.pathsep}{ROOT}"}
USER = "user_policy:policy"
TINY = ["--scenarios", "nominal,paper", "--seeds", "2", "--duration", "20", "--quiet"]


def run_cli(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "benchmarks.runner.compare", *args],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        check=check,
        timeout=600,
    )


def metrics_by_job(out: Path) -> dict[tuple, dict]:
    episodes = json.loads((out / "episodes.json").read_text())["episodes"]
    return {(e["scenario"], e["policy"], e["seed"]): e["metrics"] for e in episodes}


@pytest.mark.integration
def test_cli_end_to_end_writes_tables_and_figures(tmp_path):
    run_cli(
        "--policies",
        f"{USER},user_policy:make_policy",
        *TINY,
        "--workers",
        "2",
        "--out",
        str(tmp_path),
    )
    assert len(metrics_by_job(tmp_path)) == 2 * 2 * 2
    header = (tmp_path / "episodes.csv").read_text().splitlines()[0].split(",")
    assert {"scenario", "policy", "seed", "rms_distance", "settling_time_0p5"} <= set(header)
    payload = json.loads((tmp_path / "episodes.json").read_text())
    assert payload["config"]["seeds"] == 2 and "numpy" in payload["versions"]
    summary = (tmp_path / "summary.md").read_text()
    assert "## nominal" in summary and "**" in summary
    assert "| policy | failed | RMS d [m] |" in summary
    for name in ("track_nominal", "distance_paper", "bars_rms_distance"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 10_000
    # A factory and an instance of the same policy meet identical disturbances.
    jobs = metrics_by_job(tmp_path)
    for (scenario, policy, seed), metrics in jobs.items():
        if policy == USER:
            twin = jobs[(scenario, "user_policy:make_policy", seed)]
            assert metrics["rms_distance"] == twin["rms_distance"]


def test_results_do_not_depend_on_the_number_of_workers(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    one = main(
        [
            "--policies",
            USER,
            *TINY,
            "--workers",
            "1",
            "--out",
            str(tmp_path / "one"),
            "--no-figures",
        ]
    )
    two = main(
        [
            "--policies",
            USER,
            *TINY,
            "--workers",
            "2",
            "--out",
            str(tmp_path / "two"),
            "--no-figures",
        ]
    )
    assert [r["metrics"] for r in one] == [r["metrics"] for r in two]
    paper = [r for r in one if r["scenario"] == "paper"]
    assert paper[0]["metrics"]["rms_distance"] != paper[1]["metrics"]["rms_distance"]


def test_interrupted_run_resumes_without_recomputing(tmp_path):
    args = [
        "--policies",
        USER,
        "--scenarios",
        "paper",
        "--seeds",
        "4",
        "--duration",
        "60",
        "--workers",
        "1",
        "--quiet",
        "--no-figures",
        "--out",
        str(tmp_path),
    ]
    proc = subprocess.Popen(
        [sys.executable, "-m", "benchmarks.runner.compare", *args],
        cwd=ROOT,
        env=ENV,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    episodes = tmp_path / "episodes" / "paper" / "user_policy-policy"
    deadline = time.time() + 300
    while time.time() < deadline and not list(episodes.glob("seed_*.json")):
        time.sleep(0.1)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done = {p.name: p.stat().st_mtime_ns for p in episodes.glob("seed_*.json")}
    assert 1 <= len(done) < 4
    assert not (tmp_path / "episodes.json").exists()
    run_cli(*args)
    after = {p.name: p.stat().st_mtime_ns for p in episodes.glob("seed_*.json")}
    assert len(after) == 4
    assert all(after[name] == mtime for name, mtime in done.items())  # reused, not recomputed
    assert not list(tmp_path.rglob("*.tmp*"))


def test_a_damaged_time_series_is_flown_again_not_a_traceback(tmp_path, monkeypatch):
    """Was: a cut-short seed_0.npz passed the cache (its record was whole) and every later run
    of the command ended in zipfile.BadZipFile while drawing the figures."""
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    argv = ["--policies", USER, "--scenarios", "paper", "--seeds", "2", "--duration", "10"]
    argv += ["--workers", "1", "--quiet", "--out", str(tmp_path)]
    main(argv)
    series = tmp_path / "episodes" / "paper" / "user_policy-policy" / "seed_0.npz"
    whole = series.read_bytes()
    series.write_bytes(whole[: len(whole) // 2])
    untouched = series.with_name("seed_1.json").stat().st_mtime_ns  # seed 1 keeps no series
    main(argv)
    assert series.read_bytes() == whole  # flown again, bit for bit
    assert series.with_name("seed_1.json").stat().st_mtime_ns == untouched
    assert (tmp_path / "figures").is_dir()


def test_the_summary_opens_with_the_overview_and_lists_every_figure(tmp_path, monkeypatch):
    """Was: summary.md had neither the console's overview nor a word on the figures."""
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    argv = ["--scenarios", "paper", "--seeds", "2", "--duration", "10", "--workers", "1"]
    main(["--policies", USER, *argv, "--quiet", "--out", str(tmp_path)])
    summary = (tmp_path / "summary.md").read_text()
    lines = summary.splitlines()
    assert lines[0] == "# Benchmark summary" and lines[2].startswith("RMS distance to the path")
    assert lines[4:6] == ["| policy | paper |", "|---|---:|"]
    assert re.fullmatch(rf"\| {USER} \| [\d.]+ \|", lines[6])
    figures = sorted(p.name for p in (tmp_path / "figures").iterdir())
    listed = re.findall(r"^- \[`([^`]+)`\]\(figures/\1\): \S.{20,}$", summary, re.M)
    assert len(figures) == 2 + 7 and sorted(listed) == figures  # track, distance, 7 bar charts
    assert summary.index("## Figures") < summary.index("## paper")


def test_the_cache_keeps_the_series_the_figures_draw_and_resumes_across_the_choice(
    tmp_path, monkeypatch
):
    """The episode cache was 124 MB of the main job's 126: every episode's time series, though
    the figures draw the first seed's only. A run keeps those by default, --trajectories all
    keeps every one; records without a series are rerun only when a series is wanted, and a
    cache with every series (as runs wrote before) is reused as it is."""
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    argv = ["--policies", USER, "--scenarios", "paper", "--seeds", "2", "--duration", "10"]
    argv += ["--workers", "1", "--quiet", "--no-figures", "--out", str(tmp_path)]
    first = main(argv)
    episodes = tmp_path / "episodes" / "paper" / "user_policy-policy"

    def files() -> dict[str, int]:
        return {p.name: p.stat().st_mtime_ns for p in episodes.iterdir()}

    before = files()
    assert sorted(before) == ["seed_0.json", "seed_0.npz", "seed_1.json"]
    assert [r["trajectory"] for r in first] == [
        "episodes/paper/user_policy-policy/seed_0.npz",
        None,
    ]
    every = main([*argv, "--trajectories", "all"])  # seed 1 reruns to store its series
    after = files()
    assert sorted(after) == ["seed_0.json", "seed_0.npz", "seed_1.json", "seed_1.npz"]
    assert (
        after["seed_0.json"] == before["seed_0.json"]
        and after["seed_0.npz"] == before["seed_0.npz"]
    )
    assert after["seed_1.json"] != before["seed_1.json"]
    assert [r["metrics"] for r in every] == [r["metrics"] for r in first]  # the same episodes
    from auv_gym.sim.trajectory import Trajectory

    series = Trajectory.load(tmp_path / every[1]["trajectory"])
    assert series.metadata["seed"] == 1
    again = main(argv)  # a cache with every series: reused, nothing reruns or is deleted
    assert files() == after and [r["metrics"] for r in again] == [r["metrics"] for r in first]


def test_unknown_names_and_missing_agent_give_clear_errors(tmp_path):
    bad = run_cli("--policies", "lqr", *TINY, "--out", str(tmp_path), check=False)
    assert bad.returncode != 0 and "unknown policy 'lqr'" in bad.stderr
    bad = run_cli(
        "--policies", USER, "--scenarios", "hurricane", "--out", str(tmp_path), check=False
    )
    assert bad.returncode != 0 and "unknown scenario ['hurricane']" in bad.stderr
    with pytest.raises(FileNotFoundError, match="does not exist"):
        check_policy_spec(f"agent:{tmp_path / 'missing_agent'}")
    with pytest.raises(ValueError, match="cannot import"):
        check_policy_spec("user_policy_nowhere:policy")


def test_scenario_file_documents_every_scenario():
    scenarios = load_scenarios()
    assert set(scenarios) == {
        "nominal",
        "paper",
        "current",
        "uncertain",
        "fins",
        "line",
        "waypoints",
        "storm",
        "current_turning",
        "current_vertical",
        "line_current",
        "deep_helix",
        "deep_survey",
        "coastal_no_waves",
        "coastal",
        "near_surface_waves",
        "realistic_actuators",
        "realistic_sensors",
        "realistic",
        "as_built_helix",
        "as_built_survey",
        "as_built_coastal",
        "torpedo_helix",
        "torpedo_survey",
        "torpedo_as_built",
        "six_dof_helix",
        "six_dof_survey",
        "six_dof_as_built",
    }
    assert all(len(s.description) > 20 for s in scenarios.values())
    assert scenarios["fins"].controller == {"actuator": "fins"}
    assert scenarios["realistic_actuators"].controller == {"actuator": "realistic"}
    assert scenarios["realistic"].controller == {"actuator": "realistic"}
    assert scenarios["near_surface_waves"].env["waves"] == "sea_state_4"
    assert select("all", list(scenarios), "scenario") == list(scenarios)
    torpedo = [s for s in scenarios.values() if s.env.get("vehicle") == "torpedo"]
    assert len(torpedo) == 3  # `vehicle = "torpedo"` in the file is the env's vehicle
    assert all(s.env["plant"] == "6dof" and s.env["actuator"] == "realistic" for s in torpedo)
    assert all(s.controller == {"actuator": "realistic"} for s in torpedo)
    for s in torpedo:  # each has a REMUS 100 twin: the same env but the vehicle
        twin = scenarios[s.name.replace("torpedo_", "six_dof_")]
        assert {k: v for k, v in s.env.items() if k != "vehicle"} == twin.env


# ------------------------------------------------ the vehicle file in the episode cache
REMUS_FILE = ROOT / "auv_gym" / "vehicle" / "data" / "remus100.toml"
WEAK = {"X_max = 50.0": "X_max = 5.0", "M_max = 10.0": "M_max = 1.0", "N_max = 10.0": "N_max = 1.0"}


def vehicle_scenario(folder: Path) -> Path:
    """A scenario file naming a copy of the REMUS 100 file beside it by a relative path."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(REMUS_FILE, folder / "cache_auv.toml")
    scenarios = folder / "scenarios.toml"
    scenarios.write_text('[own]\ndescription = "x"\nvehicle = "cache_auv.toml"\n')
    return scenarios


def edit(file: Path, replacements: dict[str, str]) -> None:
    text = file.read_text()
    for old, new in replacements.items():
        assert old in text
        text = text.replace(old, new)
    file.write_text(text)


def test_an_edited_vehicle_file_reruns_its_cached_episodes(tmp_path, monkeypatch):
    """Was: the fingerprint held the vehicle's path, so a rerun into the same --out after
    weakening the vehicle file's actuators reused the old episode (10.109 m, silently; a fresh
    --out gave 10.671 m). Now the vehicle's values enter: an edit reruns, a comment or another
    folder does not, and the record names the values' digest, never the path."""
    scenarios = vehicle_scenario(tmp_path / "study")
    monkeypatch.chdir(tmp_path / "study")
    argv = ["--policies", "pid_los", "--scenario-file", "scenarios.toml", "--seeds", "1"]
    argv += ["--duration", "20", "--workers", "1", "--quiet", "--no-figures"]
    argv += ["--out", str(tmp_path / "out")]  # in this process: one code digest throughout
    record_file = tmp_path / "out" / "episodes" / "own" / "pid_los" / "seed_0.json"

    def rms() -> float:
        (record,) = main(argv)
        return record["metrics"]["rms_distance"]

    assert rms() == pytest.approx(10.109, abs=1e-3)
    first = json.loads(record_file.read_text())
    edit(tmp_path / "study" / "cache_auv.toml", WEAK)
    assert rms() == pytest.approx(10.671, abs=1e-3)  # rerun, as into a fresh --out
    second = json.loads(record_file.read_text())
    assert second["fingerprint"] != first["fingerprint"]
    assert second["vehicle_digest"] != first["vehicle_digest"]
    assert re.fullmatch(r"[0-9a-f]{16}", second["vehicle_digest"])
    assert "cache_auv" not in json.dumps(second)  # no path in the record
    mtime = record_file.stat().st_mtime_ns
    edit(tmp_path / "study" / "cache_auv.toml", {"# REMUS 100": "# my REMUS 100"})
    monkeypatch.chdir(tmp_path)  # another folder, the same file: the cache holds
    argv[argv.index("scenarios.toml")] = str(scenarios.relative_to(tmp_path))
    assert rms() == pytest.approx(10.671, abs=1e-3)
    assert record_file.stat().st_mtime_ns == mtime


def test_the_suites_chunk_fingerprint_follows_the_vehicle_files_values(tmp_path, monkeypatch):
    """evaluate-suite's cache (`Chunk.fingerprint`) had the same gap: the default vehicle's file
    edited, its chunks were reused."""
    from auv_gym.vehicle import record
    from benchmarks.catalog.tasks import task_set
    from benchmarks.runner import jobs
    from benchmarks.runner.suite_chunks import Chunk, resolve_policy

    shipped = tmp_path / "data"
    shutil.copytree(record.VEHICLE_DIRECTORY, shipped)
    monkeypatch.setattr(record, "VEHICLE_DIRECTORY", shipped)
    monkeypatch.setattr(jobs, "VEHICLE_DIRECTORY", shipped, raising=False)
    policy = resolve_policy("pid_los")
    chunk = Chunk(policy.name, policy.runs[0], task_set("test_tight_helix"), 20.0, 10.0)
    before = chunk.fingerprint()
    edit(shipped / "remus100.toml", {"# [kg] W/g": "# [kg] the weight over g"})  # a comment
    assert chunk.fingerprint() == before
    edit(shipped / "remus100.toml", WEAK)
    assert chunk.fingerprint() != before


def test_the_shipped_vehicle_files_enter_the_fingerprint(tmp_path, monkeypatch):
    """The shipped .toml files are data, not the .py sources the code digest holds: an edit of
    torpedo.toml (or of remus100.toml, the default's) changes the fingerprints of the episodes
    that fly it, and of no other."""
    from auv_gym.vehicle import record
    from benchmarks.runner import jobs

    shipped = tmp_path / "data"
    shutil.copytree(record.VEHICLE_DIRECTORY, shipped)
    monkeypatch.setattr(record, "VEHICLE_DIRECTORY", shipped)
    monkeypatch.setattr(jobs, "VEHICLE_DIRECTORY", shipped, raising=False)
    scenarios = load_scenarios()
    torpedo = jobs.Job("pid_los", scenarios["torpedo_helix"], 0, 10.0, 5.0)
    remus = jobs.Job("pid_los", scenarios["six_dof_helix"], 0, 10.0, 5.0)
    before = torpedo.fingerprint(), remus.fingerprint()
    edit(shipped / "torpedo.toml", {"rpm_max = 1525.0": "rpm_max = 1400.0"})
    assert torpedo.fingerprint() != before[0] and remus.fingerprint() == before[1]
    edit(shipped / "remus100.toml", WEAK)
    assert remus.fingerprint() != before[1]
    # A name and a copy of its file elsewhere are the same vehicle: the same digest.
    copy = shutil.copy(shipped / "torpedo.toml", tmp_path / "copy.toml")
    assert jobs.vehicle_digest(copy) == jobs.vehicle_digest("torpedo")
    assert jobs.vehicle_digest(None) == jobs.vehicle_digest("remus100")


def test_a_relative_vehicle_file_lies_beside_the_scenario_file(tmp_path, monkeypatch):
    """Was: resolved against the current folder, so a scenario file that worked from its own
    folder failed from any other ("vehicle file cache_auv.toml: cannot be read")."""
    from auv_gym.sim.config import config_from_kwargs

    scenarios = vehicle_scenario(tmp_path / "study")
    with open(scenarios, "a") as f:
        f.write('\n[in_env]\nenv = { vehicle = "cache_auv.toml" }\n')
        f.write(f'\n[absolute]\nvehicle = "{tmp_path / "study" / "cache_auv.toml"}"\n')
        f.write(
            '\n[named]\nvehicle = "torpedo"\nenv = { plant = "6dof", actuator = "realistic" }\n'
        )
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    loaded = load_scenarios(Path("..") / "study" / "scenarios.toml")
    beside = str(Path("..") / "study" / "cache_auv.toml")
    assert loaded["own"].env == {"vehicle": beside}
    assert loaded["in_env"].env == {"vehicle": beside}
    assert loaded["absolute"].env["vehicle"] == str(tmp_path / "study" / "cache_auv.toml")
    assert loaded["named"].env["vehicle"] == "torpedo"
    assert config_from_kwargs(loaded["own"].env).vehicle == "remus100"
    # A file that is not beside the scenario file is named as it would be opened.
    (tmp_path / "study" / "cache_auv.toml").unlink()
    with pytest.raises(ValueError, match=r"scenario 'own': vehicle file \.\./study/cache_auv"):
        load_scenarios(Path("..") / "study" / "scenarios.toml")


@pytest.mark.integration
def test_ray_backend_matches_local_processes(tmp_path, monkeypatch):
    pytest.importorskip("ray")
    monkeypatch.setenv("PYTHONPATH", ENV["PYTHONPATH"])  # Ray workers import the user policy
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    common = [
        "--policies",
        USER,
        "--scenarios",
        "paper",
        "--seeds",
        "2",
        "--duration",
        "20",
        "--quiet",
        "--no-figures",
    ]
    local = main([*common, "--workers", "1", "--out", str(tmp_path / "local")])
    import ray

    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)  # the caller's cluster
    try:
        remote = main([*common, "--backend", "ray", "--out", str(tmp_path / "ray")])
    finally:
        ray.shutdown()
    assert [r["metrics"] for r in local] == [r["metrics"] for r in remote]


# ----------------------------------------------------- usage errors (issue 11, item 4)
def usage_error(capsys, main_function, argv: list[str]) -> str:
    """The one stderr line of a CLI refusing ``argv`` with exit code 2."""
    with pytest.raises(SystemExit) as caught:
        main_function(argv)
    assert caught.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--policies", ""], "--policies must name at least one, got ''"),
        (["--policies", " , "], "--policies has an empty name"),
        (["--policies", "fbsm,,backstepping"], "--policies has an empty name"),
        (["--policies", f"{USER},fbsm,{USER}"], f"--policies names ['{USER}'] more than once"),
        (["--scenarios", "hurricane"], "unknown scenario ['hurricane']"),
        (["--scenarios", ""], "--scenarios must name at least one"),
        (["--scenarios", "paper,paper"], "--scenarios names ['paper'] more than once"),
        (["--seeds", "0"], "--seeds must be an integer in [1, 100000], got 0"),
        (["--seeds", "x"], "argument --seeds: invalid int value: 'x'"),
        (["--duration", "nan"], "--duration must be a finite number in (0, 1e+06] s, got nan"),
        (["--duration", "-5"], "--duration must be"),
        (["--transient", "30"], "--transient must be a finite number in [0, 20) s, got 30.0"),
        (["--workers", "0"], "--workers must be an integer in [1, 1024], got 0"),
        (["--address", "auto"], "--address needs --backend ray"),
        (
            ["--scenario-file", "/nonexistent.toml"],
            "scenario file /nonexistent.toml: cannot be read (No such",
        ),
        (["--policies", "lqr"], "unknown policy 'lqr'"),
    ],
)
def test_bad_arguments_exit_2_with_one_line_before_any_work(argv, message, tmp_path, capsys):
    """Was: `--policies ""` exited 0 with an empty summary, duplicated names wrote duplicated
    rows, and errors were tracebacks or exit code 1."""
    out = tmp_path / "out"
    base = ["--policies", USER, "--scenarios", "nominal", "--seeds", "1", "--duration", "20"]
    err = usage_error(capsys, main, [*base, "--out", str(out), *argv])
    assert err.startswith("python -m benchmarks.runner.compare: error: ") and message in err, err
    assert not out.exists()  # refused before the output folder was even created


@pytest.mark.parametrize("where", ["under_a_file", "a_file", "proc"])
def test_unwritable_out_is_refused_before_the_first_episode(where, tmp_path, capsys, monkeypatch):
    """Was: a 60-line traceback after running the first episode."""
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    out = {"under_a_file": blocker / "out", "a_file": blocker, "proc": Path("/proc/auv_out")}
    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    import benchmarks.runner.compare

    def no_episodes(*args, **kwargs):
        raise AssertionError("an episode ran")

    monkeypatch.setattr(benchmarks.runner.compare, "run_jobs", no_episodes)
    err = usage_error(
        capsys,
        main,
        [
            "--policies",
            USER,
            "--scenarios",
            "nominal",
            "--seeds",
            "1",
            "--duration",
            "20",
            "--out",
            str(out[where]),
        ],
    )
    assert f"--out '{out[where]}' is not a writable folder" in err


def test_unwritable_out_in_a_subprocess_is_one_line_without_traceback(tmp_path):
    (tmp_path / "file.txt").write_text("")
    bad = run_cli(
        "--policies", USER, *TINY, "--out", str(tmp_path / "file.txt" / "out"), check=False
    )
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.splitlines() == [
        f"python -m benchmarks.runner.compare: error: --out '{tmp_path / 'file.txt' / 'out'}' "
        "is not a writable folder: Not a directory"
    ]


def test_two_policies_writing_the_same_files_are_refused(tmp_path, capsys):
    """`ppo:a/b` and `ppo:a_b` both store episodes under ppo-a_b/: one would overwrite the other."""
    for name in ("a/b", "a_b"):
        shutil.copytree(ROOT / "benchmarks" / "agents" / "ppo_generalist", tmp_path / name)
    specs = f"agent:{tmp_path / 'a/b'},agent:{tmp_path / 'a_b'}"
    err = usage_error(capsys, main, ["--policies", specs, "--out", str(tmp_path / "out")])
    assert "share the label" in err


def test_a_damaged_agent_is_refused_before_the_first_episode(tmp_path, capsys):
    agent = shutil.copytree(ROOT / "benchmarks" / "agents" / "ppo_generalist", tmp_path / "agent")
    stats = dict(np.load(agent / "vecnormalize.npz"))
    np.savez(agent / "vecnormalize.npz", **{**stats, "clip_obs": np.float64("nan")})
    err = usage_error(capsys, main, ["--policies", f"agent:{agent}", "--out", str(tmp_path / "o")])
    assert f"policy 'agent:{agent}'" in err and "clip_obs is not finite" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--policies", ""], "--policies must name at least one"),
        (["--policies", "fbsm,fbsm"], "--policies names ['fbsm'] more than once"),
        (["--policies", "fbsm,,backstepping"], "--policies has an empty name"),
        (["--control-dt", "0.015"], "control_dt = 0.015 s must be a whole multiple"),
        (["--duration", "0"], "--duration must be a finite number in (0, 1e+06] s, got 0.0"),
        (["--transient", "60"], "--transient must be a finite number in [0, 60) s"),
        (["--dpi", "5"], "--dpi must be an integer in [20, 1200], got 5"),
        (["--seed", "-1"], "--seed must be non-negative, got -1"),
        (["--policies", "agent:/nonexistent"], "agent /nonexistent does not exist"),
    ],
)
def test_paper_figures_refuses_bad_arguments_in_one_line(argv, message, tmp_path, capsys):
    from benchmarks.reports.paper_figures import main as paper_main

    out = tmp_path / "out"
    err = usage_error(capsys, paper_main, ["--duration", "60", "--out", str(out), *argv])
    assert (
        err.startswith("python -m benchmarks.reports.paper_figures: error: ") and message in err
    ), err
    assert not out.exists()
    blocker = tmp_path / "file.txt"
    blocker.write_text("")
    err = usage_error(capsys, paper_main, ["--out", str(blocker / "out")])
    assert f"--out '{blocker / 'out'}' is not a writable folder" in err


# ------------------------------------------------ workers die with the parent (item 4)
def process_table() -> dict[int, tuple[int, str]]:
    """pid → (parent pid, state) of the live processes (Linux /proc)."""
    table = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        state, ppid = text[text.rindex(")") + 2 :].split()[:2]
        table[int(stat.parent.name)] = (int(ppid), state)
    return table


def descendants(pid: int) -> set[int]:
    table = process_table()
    found, frontier = set(), {pid}
    while frontier:
        frontier = {p for p, (ppid, _) in table.items() if ppid in frontier} - found
        found |= frontier
    return found


def cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def alive(pid: int) -> bool:
    state = process_table().get(pid, (0, "Z"))[1]
    return state not in ("Z", "X")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_killed_compare_leaves_no_worker_running(tmp_path):
    """Was: after SIGKILL of `compare --workers 2` the workers ran on (their episodes and the
    queued ones). Now they get SIGKILL with their parent (prctl PR_SET_PDEATHSIG)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "benchmarks.runner.compare",
            "--policies",
            USER,
            "--scenarios",
            "paper",
            "--seeds",
            "8",
            "--duration",
            "6000",
            "--workers",
            "2",
            "--quiet",
            "--no-figures",
            "--out",
            str(tmp_path),
        ],
        cwd=ROOT,
        env=ENV,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.time() + 120
        workers: set[int] = set()
        while time.time() < deadline and len(workers) < 2:
            time.sleep(0.2)
            workers = {p for p in descendants(proc.pid) if b"spawn_main" in cmdline(p)}
        assert len(workers) == 2, "the workers never started"
        time.sleep(3.0)  # into their first episodes
        children = descendants(proc.pid)
        assert all(alive(p) for p in workers)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    deadline = time.time() + 5
    while time.time() < deadline and any(alive(p) for p in children):
        time.sleep(0.1)
    assert not [p for p in children if alive(p)]


def test_a_scenario_the_env_refuses_is_named_before_any_episode(tmp_path, capsys):
    scenarios = tmp_path / "scenarios.toml"
    scenarios.write_text(
        '[ok]\ndescription = "fine"\n\n[bad]\ndescription = "no"\nenv = { control_dt = 0.015 }\n'
    )
    out = tmp_path / "out"
    err = usage_error(
        capsys, main, ["--policies", "fbsm", "--scenario-file", str(scenarios), "--out", str(out)]
    )
    assert "scenario 'bad': control_dt = 0.015 s must be a whole multiple" in err
    assert not out.exists()
    scenarios.write_text("[bad]\nenv = 3\n")
    err = usage_error(capsys, main, ["--scenario-file", str(scenarios), "--out", str(out)])
    assert "scenario 'bad': env must be a table" in err
    scenarios.write_text("[bad]\ndescription = 3\n")  # was accepted
    err = usage_error(capsys, main, ["--scenario-file", str(scenarios), "--out", str(out)])
    assert "scenario 'bad': description must be text, got 3" in err
    scenarios.write_text("not toml [")
    err = usage_error(capsys, main, ["--scenario-file", str(scenarios), "--out", str(out)])
    assert f"scenario file {scenarios}: not valid TOML (" in err
    scenarios.write_bytes(b"\xff\xfe[bad]\n")  # not UTF-8: the file is named too
    err = usage_error(capsys, main, ["--scenario-file", str(scenarios), "--out", str(out)])
    assert f"scenario file {scenarios}: not valid TOML (not UTF-8 text: " in err


def test_an_agent_runs_under_the_env_it_was_trained_on(tmp_path):
    """An agent carries its env: the residual agent meets the 2.0 m/s surge limit it trained
    with, the generalist its integral observation, in compare as in the suite; the controllers
    keep AUVPath3D-v0 (and their episode fingerprints)."""
    from benchmarks.catalog.policies import policy_env
    from benchmarks.runner.jobs import Job

    scenario = load_scenarios()["paper"]
    assert policy_env("fbsm") == ("AUVPath3D-v0", {})
    assert policy_env("ppo_residual") == ("AUVPath3DSpeedLimit-v0", {})
    env_id, agent_env = policy_env("ppo_generalist")
    assert env_id == "AUVPath3DPreview-v0" and agent_env["observation"]["integral_limit"] == 1.0
    job = Job("ppo_generalist", scenario, 0, 10.0, 5.0, env_id, agent_env)
    assert job.env_kwargs["surge_limit"] == "vehicle"  # REMUS 100's top speed, 2.0 m/s
    assert job.env_kwargs["observation"] == agent_env["observation"]
    assert "surge_limit" not in Job("fbsm", scenario, 0, 10.0, 5.0).env_kwargs
    bare = Job("ppo_generalist", scenario, 0, 10.0, 5.0, env_id)
    assert job.fingerprint() != bare.fingerprint()
    argv = [
        "--policies",
        "fbsm,ppo_generalist",
        "--scenarios",
        "paper",
        "--seeds",
        "1",
        "--duration",
        "10",
        "--quiet",
        "--no-figures",
        "--out",
        str(tmp_path),
    ]
    records = main(argv)
    assert {r["policy"]: r["env_id"] for r in records} == {
        "fbsm": "AUVPath3D-v0",
        "ppo_generalist": "AUVPath3DPreview-v0",
    }
    config = json.loads((tmp_path / "episodes.json").read_text())["config"]
    assert config["env_ids"] == {"fbsm": "AUVPath3D-v0", "ppo_generalist": "AUVPath3DPreview-v0"}
    assert config["agent_envs"] == {"ppo_generalist": agent_env}


def test_a_run_of_too_many_episodes_is_refused_before_the_jobs_are_listed(tmp_path, capsys):
    """Was: --seeds 100000 on every scenario listed 2.2 million jobs (620 MB, 10 s) before the
    first word; now refused at once, naming the product."""
    n = len(load_scenarios())
    t0 = time.monotonic()
    err = usage_error(
        capsys,
        main,
        ["--seeds", "100000", "--policies", "fbsm,backstepping", "--out", str(tmp_path / "out")],
    )
    assert time.monotonic() - t0 < 5.0
    assert (
        f"--seeds 100000 × {n} scenarios × 2 policies = {200_000 * n} episodes, more than 1000000"
    ) in err
    assert not (tmp_path / "out").exists()
