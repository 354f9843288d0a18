"""The reproduction checker finds every differing cell and every one-sided row."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.checks.reproduction import (
    COMPARE,
    RESULTS,
    Report,
    _rerun_arguments,
    avx512_dispatch,
    compare_episodes,
    compare_json,
    cpu_flags,
    machine_environment,
    retired_policies,
)

HEADER = "scenario,policy,seed,rms_distance,settling_time\n"


def _csv(path: Path, rows: list[str]) -> Path:
    path.write_text(HEADER + "".join(r + "\n" for r in rows))
    return path


@pytest.mark.parametrize("module", ["benchmarks.compare", "benchmarks.runner.compare"])
def test_rerun_arguments_replace_out_and_workers_only(module: str) -> None:
    """The committed results recorded compare under its former flat name; both names re-run."""
    recorded = (
        f"python -m {module} --policies fbsm,ppo --scenarios all --seeds 10 "
        "--duration 300 --workers 2 --out benchmarks/results/full --quiet"
    )
    args = _rerun_arguments(recorded, Path("/tmp/x"), 1)
    assert (
        args
        == (
            "--policies fbsm,ppo --scenarios all --seeds 10 --duration 300 --quiet "
            "--out /tmp/x --workers 1"
        ).split()
    )


def test_a_recorded_all_re_runs_the_committed_scenarios_only() -> None:
    """Scenarios added since (the torpedo's) are not rows of the committed run."""
    recorded = "python -m benchmarks.runner.compare --scenarios all --seeds 2 --out x"
    args = _rerun_arguments(recorded, Path("/tmp/x"), 1, ["paper", "fins"])
    assert args == "--seeds 2 --scenarios paper,fins --out /tmp/x --workers 1".split()
    recorded = "python -m benchmarks.runner.compare --scenarios=all --seeds 2"
    args = _rerun_arguments(recorded, Path("/y"), 2, ["nominal"])
    assert args == "--seeds 2 --scenarios nominal --out /y --workers 2".split()


def test_a_retired_agent_is_left_out_of_the_re_run_and_of_the_comparison(
    tmp_path: Path, capsys
) -> None:
    """The committed full run recorded ppo_helix, retired since: the others re-run, its rows
    stay on record and are not compared."""
    recorded = json.loads((RESULTS / "full" / "episodes.json").read_text())["config"]
    running, retired = retired_policies(recorded["policies"])
    assert retired == ["ppo_helix"]
    assert running == [p for p in recorded["policies"] if p != "ppo_helix"]
    args = _rerun_arguments(recorded["command"], Path("/x"), 1, ["paper"], running)
    assert args[args.index("--policies") + 1] == ",".join(running)
    assert args.count("--policies") == 1

    old = _csv(tmp_path / "a.csv", ["paper,fbsm,0,0.0640,31.5", "paper,ppo_helix,0,0.05,20.0"])
    new = _csv(tmp_path / "b.csv", ["paper,fbsm,0,0.0640,31.5"])
    report = Report(allow_new=False)
    compare_episodes(old, new, report, retired=["ppo_helix"])
    assert report.failures == 0
    printed = capsys.readouterr().out
    assert "1 committed rows of retired agents (ppo_helix) are not re-run" in printed
    assert "5 values compared, 0 differ" in printed


def test_a_recorded_command_that_runs_no_compare_is_refused() -> None:
    with pytest.raises(ValueError, match=r"does not run benchmarks\.compare or benchmarks\.runner"):
        _rerun_arguments("python -m benchmarks.runner.evaluate_suite --seeds 1", Path("/x"), 1)


def test_the_committed_command_is_re_run_through_the_real_module() -> None:
    recorded = json.loads((RESULTS / "full" / "episodes.json").read_text())["config"]["command"]
    assert "--seeds" in _rerun_arguments(recorded, Path("/tmp/x"), 1)
    assert COMPARE == "benchmarks.runner.compare"


def test_compare_episodes_counts_cells_and_one_sided_rows(tmp_path: Path, capsys) -> None:
    old = _csv(tmp_path / "a.csv", ["paper,fbsm,0,0.0640,31.5", "paper,fbsm,1,0.0650,30.0"])
    same = _csv(tmp_path / "b.csv", ["paper,fbsm,1,0.0650,30.0", "paper,fbsm,0,0.0640,31.5"])
    report = Report(allow_new=False)
    compare_episodes(old, same, report)
    assert report.failures == 0  # row order does not matter
    assert "10 values compared, 0 differ" in capsys.readouterr().out

    # one differing last digit, and one extra row in the new run
    changed = _csv(
        tmp_path / "c.csv",
        ["paper,fbsm,0,0.0641,31.5", "paper,fbsm,1,0.0650,30.0", "paper,ppo,0,0.5,40.0"],
    )
    strict = Report(allow_new=False)
    compare_episodes(old, changed, strict)
    assert strict.failures == 2
    lenient = Report(allow_new=True)
    compare_episodes(old, changed, lenient)
    assert lenient.failures == 1
    assert "0.0640 -> 0.0641" in capsys.readouterr().out


def test_learned_policies_reproduce_within_float32_rounding_classical_ones_exactly(
    tmp_path: Path, capsys
) -> None:
    old = _csv(
        tmp_path / "a.csv", ["paper,fbsm,0,0.0640,31.5", "paper,ppo_generalist,0,0.0500,20.0"]
    )
    near = ["paper,fbsm,0,0.06400000001,31.5", "paper,ppo_generalist,0,0.05000000001,20.0"]
    report = Report(allow_new=False)
    compare_episodes(old, _csv(tmp_path / "b.csv", near), report, learned=["ppo_generalist"])
    assert report.failures == 1  # fbsm's last digits: a difference; ppo_generalist's: rounding
    printed = capsys.readouterr().out
    assert "0.0640 -> 0.06400000001" in printed
    assert "differing values by policy: fbsm 1" in printed
    assert "1 values of the learned policies (ppo_generalist) differ within 1e-06" in printed
    far = ["paper,fbsm,0,0.0640,31.5", "paper,ppo_generalist,0,0.0501,20.0"]  # 2e-3 relative
    report = Report(allow_new=False)
    compare_episodes(old, _csv(tmp_path / "c.csv", far), report, learned=["ppo_generalist"])
    assert report.failures == 1


def test_compare_json_ignores_wall_times_only(tmp_path: Path) -> None:
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.write_text(json.dumps({"wall_time_s": 1.0, "metrics": {"fbsm": {"rms": [0.1, 0.2]}}}))
    b.write_text(json.dumps({"wall_time_s": 9.0, "metrics": {"fbsm": {"rms": [0.1, 0.2]}}}))
    report = Report(allow_new=False)
    compare_json("m", a, b, report)
    assert report.failures == 0
    b.write_text(json.dumps({"wall_time_s": 9.0, "metrics": {"fbsm": {"rms": [0.1, 0.25]}}}))
    compare_json("m", a, b, report)
    assert report.failures == 1


def test_a_keep_folder_it_could_not_write_is_refused_before_any_rerun(tmp_path: Path, capsys):
    """Was: found by the re-run of compare, minutes later, as a CalledProcessError traceback."""
    from benchmarks.checks.reproduction import main

    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(SystemExit) as stop:
        main(["--keep", str(blocker)])
    assert stop.value.code == 2
    assert (
        f"--keep '{blocker}' cannot be written as a folder: it is a file, not a folder"
        in capsys.readouterr().err
    )


def test_a_metric_added_since_the_results_is_listed_not_an_error(tmp_path: Path, capsys) -> None:
    """The committed files predate `mean_path_speed`: a re-run holds it, every shared cell must
    still match, and any other new column is still an error."""
    old = _csv(tmp_path / "a.csv", ["paper,fbsm,0,0.0640,31.5"])
    new = tmp_path / "b.csv"
    new.write_text(HEADER.rstrip("\n") + ",mean_path_speed\n" + "paper,fbsm,0,0.0640,31.5,1.0002\n")
    report = Report(allow_new=False)
    compare_episodes(old, new, report)
    assert report.failures == 0
    assert "1 of metrics newer than these results: ['mean_path_speed']" in capsys.readouterr().out
    other = tmp_path / "c.csv"
    other.write_text(HEADER.rstrip("\n") + ",pace\n" + "paper,fbsm,0,0.0640,31.5,1.0\n")
    compare_episodes(old, other, report)
    assert report.failures == 1
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.write_text(json.dumps({"metrics": {"fbsm": {"rms": 0.1}}}))
    b.write_text(json.dumps({"metrics": {"fbsm": {"rms": 0.1, "mean_path_speed": 1.0}}}))
    compare_json("m", a, b, report)
    assert report.failures == 1  # unchanged
    b.write_text(json.dumps({"metrics": {"fbsm": {"rms": 0.1, "pace": 1.0}}}))
    compare_json("m", a, b, report)
    assert report.failures == 2


def test_re_runs_run_as_an_avx2_machine_where_the_cpu_can(tmp_path, capsys, monkeypatch) -> None:
    """As the committed results' machine: NumPy without its AVX-512 loops and OpenBLAS on its
    Haswell kernels where the CPU has AVX2 and FMA; a CPU without them keeps OpenBLAS's choice
    (a kernel it lacks would crash the run), and "native" changes nothing."""
    monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)
    monkeypatch.delenv("NPY_DISABLE_CPU_FEATURES", raising=False)
    cpuinfo = tmp_path / "cpuinfo"
    cpuinfo.write_text("processor\t: 0\nflags\t\t: fpu sse2 avx avx2 fma avx512f\n")
    flags = cpu_flags(cpuinfo)
    assert {"avx2", "fma", "avx512f"} <= flags
    env = machine_environment("avx2", flags, ["X86_V4", "AVX512_ICL"])
    assert env["OPENBLAS_CORETYPE"] == "Haswell"
    assert env["NPY_DISABLE_CPU_FEATURES"] == "X86_V4 AVX512_ICL"
    old_cpu = machine_environment("avx2", {"fpu", "sse2", "avx"}, [])
    assert "OPENBLAS_CORETYPE" not in old_cpu and "NPY_DISABLE_CPU_FEATURES" not in old_cpu
    assert "lacks avx2, fma" in capsys.readouterr().err
    native = machine_environment("native", flags, ["X86_V4"])
    assert "OPENBLAS_CORETYPE" not in native and "NPY_DISABLE_CPU_FEATURES" not in native
    assert cpu_flags(tmp_path / "missing") == set()
    assert all(name == "X86_V4" or name.startswith("AVX512") for name in avx512_dispatch())


def test_an_unknown_machine_is_refused_before_any_rerun(capsys) -> None:
    from benchmarks.checks.reproduction import main

    with pytest.raises(SystemExit) as stop:
        main(["--machine", "avx3"])
    assert stop.value.code == 2
    assert "--machine must be one of avx2, native, got 'avx3'" in capsys.readouterr().err


def test_held_out_re_runs_reach_an_ensemble_under_its_members_env(tmp_path, monkeypatch, capsys):
    """Was: `--agents` read each agent folder's metadata.json for its env id and stopped at the
    shipped ensemble, whose folder holds ensemble.json and its members' folders instead."""
    import shutil

    import benchmarks.training
    from benchmarks.catalog.policies import AGENTS_DIR
    from benchmarks.checks.reproduction import compare_held_out
    from controllers.agent import check_agent

    agents = tmp_path / "agents"
    shutil.copytree(AGENTS_DIR / "ppo_residual_as_built", agents / "ensemble")
    assert not (agents / "ensemble" / "metadata.json").exists()
    recorded = json.loads((agents / "ensemble" / "held_out_evaluation.json").read_text())
    calls = []

    def evaluation(agent, duration, env_id=None):  # the recorded run, 10 x 200 s, stands in
        calls.append((Path(agent).name, duration, env_id))
        return recorded

    monkeypatch.setattr(benchmarks.training, "held_out_evaluation", evaluation)
    report = Report(allow_new=False)
    (tmp_path / "out").mkdir()
    compare_held_out(agents, tmp_path / "out", report)
    # no env id given: held_out_evaluation takes the one the ensemble's members record
    assert calls == [("ensemble", 200.0, None)]
    assert check_agent(agents / "ensemble").metadata["env_id"] == "AUVPath3DSpeedLimit-v0"
    assert report.failures == 0
    assert "ensemble held-out: 133 values compared, 0 differ" in capsys.readouterr().out

    recorded = {**recorded, "summary": {**recorded["summary"], "rms_distance_mean": 0.3}}
    compare_held_out(agents, tmp_path / "out", report)
    assert report.failures == 1
