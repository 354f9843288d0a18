"""The benchmark CLI (`python -m benchmarks.compare`) end to end on tiny grids."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from benchmarks.compare import main
from benchmarks.policies import check_policy_spec
from benchmarks.scenarios import load_scenarios, select

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": f"{ROOT / 'tests'}{os.pathsep}{ROOT}"}
USER = "user_policy:policy"
TINY = ["--scenarios", "nominal,paper", "--seeds", "2", "--duration", "20", "--quiet"]


def run_cli(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "benchmarks.compare", *args],
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
    assert "## nominal" in summary and "| rms_distance |" in summary and "**" in summary
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
        [sys.executable, "-m", "benchmarks.compare", *args],
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


def test_unknown_names_and_missing_agent_give_clear_errors(tmp_path):
    bad = run_cli("--policies", "lqr", *TINY, "--out", str(tmp_path), check=False)
    assert bad.returncode != 0 and "unknown policy 'lqr'" in bad.stderr
    bad = run_cli(
        "--policies", USER, "--scenarios", "hurricane", "--out", str(tmp_path), check=False
    )
    assert bad.returncode != 0 and "unknown scenario ['hurricane']" in bad.stderr
    with pytest.raises(FileNotFoundError, match="does not exist"):
        check_policy_spec(f"ppo:{tmp_path / 'missing_agent'}")
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
    }
    assert all(len(s.description) > 20 for s in scenarios.values())
    assert scenarios["fins"].controller == {"actuator": "fins"}
    assert select("all", list(scenarios), "scenario") == list(scenarios)


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

    try:
        remote = main([*common, "--backend", "ray", "--out", str(tmp_path / "ray")])
    finally:
        ray.shutdown()
    assert [r["metrics"] for r in local] == [r["metrics"] for r in remote]
