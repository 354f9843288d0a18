"""Named task sets (benchmarks/tasks.toml): the split cannot leak; bad files fail early."""

from __future__ import annotations

import numpy as np
import pytest

from auv_gym.sim.config import SimConfig
from auv_gym.sim.path_generator import PathDistribution, overlaps
from auv_gym.sim.randomization import task_for_seed
from benchmarks.catalog.scenarios import load_scenarios
from benchmarks.catalog.tasks import TASKS_FILE, load_task_sets, task_set
from benchmarks.catalog.tasks import test_suite as the_test_suite

BENCHMARK_SCENARIOS = [
    "nominal",
    "paper",
    "current",
    "uncertain",
    "fins",
    "line",
    "waypoints",
    "storm",
]


def _helix_parameters(path):
    """(radius [m], |γ| [deg]) of a generated helix (arc-length parameterised)."""
    return path.radius, float(np.degrees(np.arcsin(abs(path.climb))))


@pytest.mark.integration
def test_training_seeds_and_draws_never_meet_a_test_episode():
    sets = load_task_sets()
    train, validation = sets["train"], sets["validation"]
    tests = the_test_suite()
    assert {s.role for s in tests} == {"test"}
    test_seeds = set().union(*(set(s.seeds) for s in tests))
    assert not test_seeds & set(validation.seeds)
    assert min(train.seeds) > max(test_seeds | set(validation.seeds))  # disjoint ranges
    # Held-out families: no test draw lies in the training support, and no training draw
    # (a sample of training seeds) lies in a held-out family's ranges.
    train_dist = SimConfig.from_kwargs(**train.env).path
    held_out = [s for s in tests if s.held_out == "train"]
    assert len(held_out) >= 2
    train_draws = [
        task_for_seed(SimConfig.from_kwargs(**train.env), seed).path for seed in train.seeds[:200]
    ]
    for s in held_out:
        config = SimConfig.from_kwargs(**s.env)
        dist = config.path
        assert overlaps(dist, train_dist) == []
        for _, seed in s.episodes():
            path = task_for_seed(config, seed).path
            if path.family == "helix":
                radius, gamma = _helix_parameters(path)
                inside_radius = train_dist.radius[0] <= radius <= train_dist.radius[1]
                inside_angle = gamma <= train_dist.climb_angle_deg[1]
                assert not (inside_radius and inside_angle), (s.name, radius, gamma)
            else:  # a line: only its angle can hold it out
                gamma = np.degrees(np.arcsin(abs(path.data[5])))
                assert gamma > train_dist.climb_angle_deg[1]
        for path in train_draws:
            if path.family == "helix" and path.family in dist.families:
                radius, gamma = _helix_parameters(path)
                low, high = dist.climb_angle_deg
                assert not (dist.radius[0] <= radius <= dist.radius[1] and low <= gamma <= high)


def test_the_test_suite_holds_the_benchmark_scenarios():
    suite = {s.name: s for s in the_test_suite()}
    scenarios = load_scenarios()
    for name in BENCHMARK_SCENARIOS:
        s = suite[f"scenario:{name}"]
        assert s.env == scenarios[name].env and s.controller == scenarios[name].controller
        assert list(s.seeds) == list(range(10))
    assert {"test_tight_helix", "test_steep", "test_wide_helix", "test_distribution"} <= set(suite)


def test_task_sets_build_their_envs():
    train = task_set("train")
    config = SimConfig.from_kwargs(**train.env)
    assert isinstance(config.path, PathDistribution) and config.randomized
    assert config.actuator == "random" and config.randomize_start
    assert task_set("validation").episodes()[0] == (task_set("validation").env, 100_000)


@pytest.mark.parametrize(
    ("name", "like", "key", "values"),
    [
        (
            "validation_as_built_start_plants",
            "validation_as_built_start",
            "plant",
            ["5dof", "6dof"],
        ),
        ("validation_as_built_plants", "validation_as_built", "plant", ["5dof", "6dof"]),
        ("validation_actuators_start", "validation_paper_start", "actuator", ["paper", "fins"]),
    ],
)
def test_a_varied_validation_set_flies_every_seed_once_per_value(name, like, key, values):
    varied = task_set(name)
    assert varied.vary == (key, tuple(values))
    episodes = varied.episodes()
    assert len(episodes) == 2 * len(varied.seeds) == 200
    assert [env[key] for env, _ in episodes[:1] + episodes[100:101]] == values
    assert [seed for _, seed in episodes[:100]] == [seed for _, seed in episodes[100:]]
    # each half is the set it varies, with its value, on seeds of its own
    base = task_set(like)
    assert {k: v for k, v in base.env.items() if k != key} == varied.env
    assert set(varied.seeds).isdisjoint(base.seeds)
    assert varied.eval_env()[key] == values
    assert task_set("validation").eval_env() == task_set("validation").env


def test_the_cross_current_validation_set_is_the_paper_start_in_the_current_scenario():
    cross, base = task_set("validation_cross_current"), task_set("validation_paper_start")
    assert cross.role == "validation" and set(cross.seeds).isdisjoint(base.seeds)
    changed = {"current", "random_current"}
    assert {k: v for k, v in cross.env.items() if k not in changed} == {
        k: v for k, v in base.env.items() if k not in changed
    }
    assert cross.env["current"] == load_scenarios()["current"].env["current"]
    config = SimConfig.from_kwargs(**cross.env)
    means = []
    for seed in cross.seeds:
        task = task_for_seed(config, seed)
        means.append(np.add(config.current.mean, task.current))
        if task.path.family == "helix":  # the current flows along or against its start tangent
            tangent = task.path.evaluate(0.0)[1]
            heading = np.degrees(np.arctan2(tangent[1], tangent[0]))
            assert abs(heading) == pytest.approx(90.0)
    means = np.array(means)
    # 0.3 m/s toward +y plus up to 0.2 m/s in any direction: 0.1-0.5 m/s, northward
    speeds = np.hypot(means[:, 0], means[:, 1])
    assert speeds.min() >= 0.1 - 1e-12 and speeds.max() <= 0.5 + 1e-12
    assert means[:, 1].min() >= 0.1 - 1e-12 and abs(means[:, 0]).max() <= 0.2 + 1e-12


def _write(tmp_path, text):
    file = tmp_path / "tasks.toml"
    file.write_text(text)
    return file


TEST = '[x]\nrole = "test"\nseeds = { first = 0, count = 5 }\n'
VALIDATION = '[x]\nrole = "validation"\nseeds = { first = 0, count = 5 }\n'
TRAIN = '[train]\nrole = "train"\nseeds = { first = 100, count = 50 }\nenv = { path = "random" }\n'


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            TRAIN + '[t]\nrole = "test"\nseeds = { first = 120, count = 5 }\nenv = {}\n',
            r"train set 'train' and test set 't' share seeds \[120, 125\): "
            "test episodes would leak",
        ),
        (
            TRAIN + '[v]\nrole = "validation"\nseeds = { first = 0, count = 101 }\nenv = {}\n',
            r"train set 'train' and validation set 'v' share seeds \[100, 101\)",
        ),
        (
            TRAIN + '[t]\nrole = "test"\nheld_out = "train"\nseeds = { first = 0, count = 5 }\n'
            'env = { path = { families = ["helix"], radius = [15.0, 20.0] } }\n',
            r"'t' is marked held_out but the training set 'train' can draw its helix paths",
        ),
        (
            '[train]\nrole = "train"\nseeds = { first = 0, count = 5 }\n'
            "env = { path = { radius = [0.0, 20.0] } }\n",
            r"task set 'train': PathDistribution radius must be positive",
        ),
        (
            '[train]\nrole = "train"\nseeds = { first = 0, count = 5 }\n'
            "env = { path = { climb_angle_deg = [0.0, 40.0] } }\n",
            r"task set 'train': PathDistribution climb_angle_deg .* exceeds the vehicle's largest",
        ),
        ('[x]\nrole = "exam"\nseeds = { first = 0, count = 5 }\n', r"role must be one of"),
        ('[x]\nrole = "test"\nseeds = { first = 0, count = 0 }\n', r"count >= 1"),
        ('[x]\nrole = "test"\nseeds = [0, 5]\n', r"seeds must be \{ first"),
        ('[x]\nrole = "test"\nseed = { first = 0, count = 5 }\n', r"unknown keys \['seed'\]"),
        (
            '[x]\nrole = "test"\nseeds = { first = 0, count = 5 }\nscenarios = ["papr"]\n',
            r"unknown scenarios \['papr'\]",
        ),
        (
            '[x]\nrole = "test"\nseeds = { first = 0, count = 5 }\ncontroller = "fins"\n',
            r"task set 'x': controller must be a table, got 'fins'",
        ),
        (  # a typo in an env key: the valid ones listed, not a Python signature's complaint
            TEST + 'env = { disturbanc = "none" }\n',
            r"task set 'x': unknown env keyword arguments \['disturbanc'\]; "
            r"valid: \[.*'disturbance'",
        ),
        (
            TEST + 'vary = { plant = ["5dof", "6dof"] }\n',
            r"task set 'x': only a validation set may vary, this one is 'test'",
        ),
        (
            VALIDATION + 'vary = { plant = ["5dof", "6dof"] }\nenv = { plant = "6dof" }\n',
            r"task set 'x': give vary.plant or plant in env/controller, not both",
        ),
        (
            VALIDATION
            + 'vary = { actuator = ["paper", "fins"] }\ncontroller = { actuator = "fins" }\n',
            r"task set 'x': give vary.actuator or actuator in env/controller, not both",
        ),
        (
            VALIDATION + 'vary = { plant = ["5dof", "7dof"] }\n',
            r"vary.plant must list two or more distinct values of \['5dof', '6dof'\], "
            r"got \['5dof', '7dof'\]",
        ),
        (VALIDATION + 'vary = { plant = ["6dof"] }\n', r"vary.plant must list two or more"),
        (
            VALIDATION + 'vary = { sensors = ["none", "typical"] }\n',
            r"vary must be a table of one key of \['actuator', 'plant'\]",
        ),
        (
            VALIDATION + 'vary = { plant = ["6dof", "5dof"] }\n'
            'env = { vehicle = "torpedo", actuator = "realistic" }\n',
            r"task set 'x', plant '5dof': vehicle 'torpedo' has no \[model_5dof\]",
        ),
        (
            '[x]\nrole = "test"\nseeds = { first = 0, count = 5 }\nscenarios = ["fins"]\n'
            'controller = { actuator = "fins" }\n',
            r"scenarios belong to a test set without env/controller/held_out",
        ),
    ],
)
def test_bad_task_files_raise_one_line_errors(tmp_path, text, match):
    with pytest.raises(ValueError, match=match) as caught:
        load_task_sets(_write(tmp_path, text))
    assert "\n" not in str(caught.value)


def test_a_relative_vehicle_file_lies_beside_the_task_file(tmp_path, monkeypatch):
    """Was: resolved against the current folder, so a task file worked from one folder only."""
    import shutil

    from auv_gym.vehicle.record import VEHICLE_DIRECTORY

    folder = tmp_path / "tasks"
    folder.mkdir()
    shutil.copy(VEHICLE_DIRECTORY / "remus100.toml", folder / "mine.toml")
    file = _write(folder, VALIDATION + 'env = { vehicle = "mine.toml" }\n')
    monkeypatch.chdir(tmp_path)  # not the task file's folder
    assert load_task_sets(file)["x"].env["vehicle"] == str(folder / "mine.toml")


def test_unknown_task_set_names_are_refused():
    with pytest.raises(ValueError, match=r"unknown task set 'trian'; valid: \[.*'train'"):
        task_set("trian")
    assert TASKS_FILE.exists()
