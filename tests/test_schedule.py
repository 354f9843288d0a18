"""Training schedules (`benchmarks.training.schedule`): a whole recipe in one file, trained by
one command. A tiny two-phase schedule end to end (the second phase starts from each seed's
agent of the first, the exported agent carries the schedule's stages, a resumed command skips
finished phases), the reference generalist's schedule as its recipe, and bad schedules refused
in one line before any work."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from benchmarks.training.config import read_zoo_config
from benchmarks.training.schedule import check_schedule, read_schedule
from benchmarks.training.seeds import validation_set
from benchmarks.training.seeds_cli import main

ROOT = Path(__file__).resolve().parents[1]
ENV_ID = "AUVPath3DPreview-v0"
SECTION = {
    "n_envs": 4,
    "n_timesteps": 512,
    "policy": "MlpPolicy",
    "normalize": True,
    "n_steps": 64,
    "batch_size": 128,
    "n_epochs": 1,
    "learning_rate": "lin_3e-4",
    "policy_kwargs": "dict(net_arch=[16])",
    "obs_scales": {"x_e": 2.0, "y_e": 2.0},
    "env_kwargs": {"observation": "preview_integral", "randomize_start": True, "max_time": 20.0},
}
SCHEDULE = {
    "options": {"eval_freq": 256, "eval_duration": 110.0, "eval_episodes": 2},
    "stages": ["envelope_guard"],
    "phases": [
        {"name": "base"},
        {
            "name": "fine",
            "n_timesteps": 256,
            "obs_scales": {"x_e": 0.25},
            "task_set": "validation_paper_start",  # selected on its own set from here on
        },
    ],
}


def _write(tmp_path: Path, schedule: dict | None = None, section: dict | None = None) -> Path:
    path = tmp_path / "schedule.yml"
    data = {ENV_ID: section or SECTION, "schedule": schedule or SCHEDULE}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _argv(config: Path, out: Path, *extra: str) -> list[str]:
    return [
        "--config",
        str(config),
        "--seeds",
        "0-1",
        "--workers",
        "2",
        "--eval-seeds",
        "100",
        "--checkpoint-freq",
        "128",
        "--out",
        str(out),
        "--quiet",
        *extra,
    ]


def test_the_generalist_schedule_is_its_recipe():
    schedule = read_schedule(ROOT / "benchmarks" / "hyperparams" / "ppo_generalist.yml")
    assert schedule is not None and schedule.env_id == ENV_ID
    assert [p.name for p in schedule.phases] == ["jump_start", "base", "precision"]
    assert schedule.phases[0].changes["jump_start"] == {"expert": "fbsm_colos", "steps": 131072}
    base, precision = schedule.phase_section(1), schedule.phase_section(2)
    assert base["n_timesteps"] == 3e6 and base["learning_rate"] == "lin_3e-4"
    assert base["env_kwargs"]["observation"] == "preview_integral"
    assert precision["n_timesteps"] == 1e6 and precision["learning_rate"] == "lin_1e-4"
    changed = {"x_e": 0.25, "x_e_integral": 0.5, "y_e": 0.5, "z_e": 0.5}
    changed |= {"y_e_integral": 1.0, "z_e_integral": 1.0}
    assert precision["obs_scales"] == {**base["obs_scales"], **changed}
    fixed = ("n_timesteps", "learning_rate", "obs_scales")  # nothing else changes
    assert {k: v for k, v in precision.items() if k not in fixed} == {
        k: v for k, v in base.items() if k not in fixed
    }
    assert [s["name"] for s in schedule.stages] == ["envelope_guard", "actuator_allocation"]
    assert schedule.options["task_set"] == "validation_paper_start"
    assert schedule.options["eval_episodes"] == 16


def test_the_mirror_recipe_trains_what_the_integral_recipe_trains():
    """sac_generalist_mirror differs from sac_generalist_integral in its exports and selection
    only: every phase trains the same section, so the integral runs are its runs."""
    folder = ROOT / "benchmarks" / "hyperparams"
    mirror = read_schedule(folder / "sac_generalist_mirror.yml")
    integral = read_schedule(folder / "sac_generalist_integral.yml")
    assert mirror is not None and integral is not None
    assert len(mirror.phases) == len(integral.phases) == 2
    for k in range(2):
        assert mirror.phase_section(k) == integral.phase_section(k)
        assert mirror.phases[k] == integral.phases[k]
    assert mirror.options == integral.options
    assert [s["name"] for s in mirror.stages] == ["mirror_symmetry", "actuator_allocation"]
    assert [s["name"] for s in integral.stages] == ["actuator_allocation"]
    assert (mirror.select_on, integral.select_on) == ("shipped", "network")


RECIPES = sorted((ROOT / "benchmarks" / "hyperparams").glob("*.yml"))


@pytest.mark.parametrize("recipe", RECIPES, ids=lambda path: path.stem)
def test_every_committed_recipe_passes_the_checks_made_before_training(recipe, tmp_path):
    """A recipe whose command would fail at its first check (a bad key, a phase that cannot
    follow the one before it, an unknown validation set) is caught here, not hours into a run."""
    algo = recipe.stem.split("_")[0]  # the files are named <algo>_<agent>
    schedule = read_schedule(recipe)
    if schedule is None:  # a one-run file of `auv-gym train`: a section per env id
        for env_id in yaml.safe_load(recipe.read_text()):
            assert read_zoo_config(recipe, env_id, algo).n_timesteps > 0
        return
    assert schedule.options.get("algo", "ppo") == algo
    configs = check_schedule(schedule, algo, tmp_path)
    assert [c.name for c in configs] == [
        f"{schedule.folder(tmp_path, k).name}.yml" for k in range(len(schedule.phases))
    ]
    for name in [schedule.options.get("task_set")] + [p.task_set for p in schedule.phases]:
        if name is not None:
            validation_set(name)  # the command's own check: a ValueError naming the set


@pytest.mark.integration
@pytest.mark.rl
def test_a_two_phase_schedule_trains_end_to_end_and_resumes(tmp_path):
    config = _write(tmp_path)
    out, agent = tmp_path / "run", tmp_path / "agent"
    assert main(_argv(config, out, "--export", str(agent))) == 0
    record = json.loads((out / "schedule.json").read_text())
    assert [p["name"] for p in record["phases"]] == ["base", "fine"]
    base, fine = (out / name for name in ("phase_1_base", "phase_2_fine"))
    for seed in (0, 1):  # each seed of the second phase started from its own first-phase agent
        meta = json.loads((fine / f"seed_{seed}" / "final" / "metadata.json").read_text())
        assert meta["warm_start"]["init_from"] == str(base / "selected" / f"agent_seed_{seed}")
        assert meta["num_timesteps"] == 256  # the phase's own budget (one rollout)
        first = json.loads((base / f"seed_{seed}" / "final" / "metadata.json").read_text())
        assert first["num_timesteps"] == 512 and "warm_start" not in first
    fine_config = yaml.safe_load((out / "configs" / "phase_2_fine.yml").read_text())[ENV_ID]
    assert "task_set" not in fine_config  # a selection option, not a hyper-parameter
    for folder, seeds in ((base, [100]), (fine, [100_200, 100_201])):
        plan = json.loads((folder / "train_seeds.json").read_text())
        assert plan["eval_seeds"] == seeds, folder
    assert fine_config["obs_scales"] == {"x_e": 0.25, "y_e": 2.0}
    assert fine_config["n_timesteps"] == 256
    exported = json.loads((agent / "metadata.json").read_text())
    assert [s["name"] for s in exported["stages"]] == ["envelope_guard"]
    assert exported["env_id"] == ENV_ID and exported["observation"]["integral_limit"] == 1.0
    from controllers.loader import load_policy

    assert [s.name for s in load_policy(agent).stages] == ["envelope_guard"]
    from benchmarks.training.evaluation import held_out_evaluation

    shipped_test = json.loads((agent / "held_out_evaluation.json").read_text())
    # the exported agent's test episodes are flown as it ships, stages on
    again = held_out_evaluation(agent, 110.0, ENV_ID)["results"]
    assert json.dumps(shipped_test["results"], sort_keys=True) == json.dumps(again, sort_keys=True)
    # Resumed when everything is done: nothing trains again, the record is rewritten the same;
    # --results then writes every seed's agent, test evaluation and curves, as a one-phase run.
    before = {p: p.stat().st_mtime_ns for p in fine.rglob("model.zip")}
    results = tmp_path / "results"
    stale = results / "agent_seed_7" / "model.zip"  # a seed an earlier run here wrote
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b"seed 7")
    (results / ".outputs.json").write_text(json.dumps({"files": ["agent_seed_7/model.zip"]}))
    assert main(_argv(config, out, "--resume", "--results", str(results))) == 0
    assert not stale.parent.exists()  # the suite would have flown it as a seed of this run
    assert {p: p.stat().st_mtime_ns for p in fine.rglob("model.zip")} == before
    for seed in (0, 1):
        assert (results / f"agent_seed_{seed}" / "model.zip").is_file()
        stages = json.loads((results / f"agent_seed_{seed}" / "metadata.json").read_text())
        assert [s["name"] for s in stages["stages"]] == ["envelope_guard"]
        test = json.loads((results / f"seed_{seed}_test_evaluation.json").read_text())
        assert len(test["results"]) == len(test["seeds"]) > 0
        last = (results / f"seed_{seed}_learning_curve.csv").read_text()
        assert last == (results / f"phase_2_fine_seed_{seed}_curve.csv").read_text()
        assert (results / f"phase_1_base_seed_{seed}_curve.csv").is_file()
    assert json.loads((results / "schedule.json").read_text())["selected_seed"] in (0, 1)
    assert (
        json.loads((out / "schedule.json").read_text())["selected_seed"] == record["selected_seed"]
    )
    # The same run selected as shipped (the schedule's stages on): nothing trains, every seed's
    # agent flies the last phase's validation once, and the export is the seed it picks.
    shipped_config = _write(tmp_path, {**SCHEDULE, "select_on": "shipped"})
    assert main(_argv(shipped_config, out, "--resume", "--export", str(agent))) == 0
    assert {p: p.stat().st_mtime_ns for p in fine.rglob("model.zip")} == before
    shipped = json.loads((out / "schedule.json").read_text())
    picked = shipped["shipped_selection"]
    assert (
        sorted(picked["seeds"]) == ["0", "1"]
        and shipped["selected_seed"] == picked["selected_seed"]
    )
    for entry in picked["seeds"].values():
        assert entry["eval_seeds"] == [100_200, 100_201]  # the last phase's validation
        assert [s["name"] for s in entry["stages"]] == ["envelope_guard"]
        assert entry["score"][0] == entry["summary"]["n_terminated"]
    scores = {int(s): (*e["score"], int(s)) for s, e in picked["seeds"].items()}
    assert picked["selected_seed"] == min(scores, key=scores.get)
    assert json.loads((agent / "metadata.json").read_text())["seed"] == picked["selected_seed"]
    assert shipped["phases"][-1]["summary"]["selected_seed"] == record["selected_seed"]


@pytest.mark.parametrize(
    ("schedule", "message"),
    [
        ({"phases": []}, r"schedule.phases must be a non-empty list"),
        (
            {"phases": [{"name": "a", "n_steps_total": 3}]},
            r"phases\[0\] \(a\): unknown keys \['n_steps_total'\]",
        ),
        ({"phases": [{"name": "a"}, {"name": "a"}]}, "phase name 'a' is used twice"),
        ({"phases": [{"name": "A b"}]}, "name must be a lower-case identifier"),
        (
            {"phases": [{"name": "a"}, {"name": "b", "init_from": "x"}]},
            "init_from belongs to the first phase",
        ),
        (
            {"phases": [{"name": "a"}], "stages": ["lowpass"]},
            r"schedule.stages: unknown stage 'lowpass'",
        ),
        (
            {"phases": [{"name": "a"}], "options": {"seeds": 3}},
            r"options: unknown keys \['seeds'\]",
        ),
        ({"phases": [{"name": "a"}], "cost": 1}, r"schedule: unknown keys \['cost'\]"),
        (
            {"phases": [{"name": "a"}], "select_on": "test"},
            r"schedule.select_on: unknown value 'test'; valid: \['network', 'shipped'\]",
        ),
        (  # without export stages the shipped agent is the network the training chose
            {"phases": [{"name": "a"}], "select_on": "shipped"},
            r"schedule.select_on: shipped needs export stages",
        ),
        (
            {"phases": [{"name": "a", "task_set": "train"}]},
            r"phases\[0\] \(a\): task_set: 'train' is not a validation set",
        ),
        (
            {"phases": [{"name": "a", "init_from": "missing/agent"}]},
            "init_from 'missing/agent' does not exist",
        ),
        ({"phases": [{"name": "a", "obs_scales": {"psi": 1.0}}]}, "phase 'a'"),
        (  # the section trains inside the guard already: the export would carry it twice
            {"phases": [{"name": "a"}], "stages": ["envelope_guard"], "section_stages": True},
            r"schedule.stages after AUVPath3DPreview-v0.stages: stages \['envelope_guard', "
            r"'envelope_guard'\] must each appear once",
        ),
    ],
)
def test_bad_schedules_are_refused_in_one_line_before_any_work(tmp_path, capsys, schedule, message):
    schedule = dict(schedule)
    section = (
        {**SECTION, "stages": ["envelope_guard"]} if schedule.pop("section_stages", 0) else None
    )
    config = _write(tmp_path, schedule, section)
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as stop:
        code = main(_argv(config, out))
        raise SystemExit(code)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert pytest.importorskip("re").search(message, err), err
    assert not (out / "phase_1_a").exists()


def test_the_exports_carry_the_stages_trained_inside_then_the_schedules(tmp_path):
    """Was: an agent trained inside the envelope guard (the section's stages) was exported with
    the schedule's stages only, and flew without the guard it had learnt inside."""
    from benchmarks.training.schedule import _with_stages

    agent = tmp_path / "agent"
    agent.mkdir()
    (agent / "metadata.json").write_text(json.dumps({"stages": [{"name": "envelope_guard"}]}))
    _with_stages(agent, ({"name": "actuator_allocation"},))
    stages = json.loads((agent / "metadata.json").read_text())["stages"]
    assert [s["name"] for s in stages] == ["envelope_guard", "actuator_allocation"]
    assert stages[0]["pitch_soft_deg"] == 35.0  # checked and filled in, as the schedule's are


def test_train_refuses_a_schedule_it_would_not_run(tmp_path, capsys):
    """Was: `auv-gym train --config SCHEDULE` trained the env section alone and said nothing,
    a recipe without its jump start or later phases."""
    from benchmarks.training.train_cli import main as train_main

    config = _write(tmp_path)
    out = tmp_path / "run"
    argv = ["--config", str(config), "--env-id", ENV_ID, "--out", str(out), "--eval-freq", "0"]
    with pytest.raises(SystemExit) as stop:
        train_main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert err.rstrip().endswith(
        f"{config} holds a schedule of 2 phase(s), which `auv-gym train` does not run (it "
        f"trains one section once): run the recipe with `auv-gym train-seeds --config {config}`"
    )
    assert not (out / "model.zip").exists() and not (out / "metadata.json").exists()
