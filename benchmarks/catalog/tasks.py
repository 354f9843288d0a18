"""Named task sets (`benchmarks/tasks.toml`): the training distribution, validation and test suite.

A `TaskSet` is a role ("train", "validation", "test"), a half-open range of reset seeds and the
`AUVPath3D-v0` keyword arguments of its episodes, with the controller keyword arguments its
policies are told (``controller``, as a scenario's: e.g. the actuator); the test suite also
holds the benchmark scenarios (`benchmarks/scenarios.toml`) by name, one set per scenario
("scenario:<name>"). An episode is the pair (env keyword arguments, seed).

A validation set may fly every seed on several plants or actuators (``vary = { plant = ["5dof",
"6dof"] }`` or ``vary = { actuator = ["paper", "fins"] }``, in place of that env argument): an
agent meant for all of them is then selected on all at once, each seed once per value, so its
score is the mean over them (`episodes`).

`load_task_sets` validates the whole file before anything runs, each problem a one-line
ValueError naming the set: unknown keys or roles, a bad seed range, env arguments the env refuses
(an impossible generator range such as radius ≤ 0 or a climb beyond the vehicle's limits names the
field), training or validation seeds that meet a test set's or each other's, and a `held_out`
test set whose paths the training distribution could draw (`auv_gym.sim.path_generator.overlaps`).

    from benchmarks.catalog.tasks import load_task_sets, task_set
    train = task_set("train")                   # .env, .seeds (a range)
    env = gym.make_vec("AUVPath3D-v0", num_envs=16, **train.env)
    env.reset(seed=train.seeds.start)
    suite = test_suite()                         # every test set, scenarios expanded
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, field
from itertools import combinations
from pathlib import Path
from typing import Any

from auv_gym.sim.config import PLANTS, SimConfig, config_from_kwargs
from auv_gym.sim.path_generator import PathDistribution, overlaps
from auv_gym.support.files import read_toml
from benchmarks.catalog.scenarios import SCENARIOS_FILE, load_scenarios, vehicle_beside

__all__ = [
    "FRESH_TASKS_FILE",
    "ROLES",
    "TASKS_FILE",
    "TaskSet",
    "load_task_sets",
    "task_set",
    "test_seeds",
    "test_suite",
]

TASKS_FILE = Path(__file__).resolve().parents[1] / "tasks.toml"
# Fresh held-out as-built episodes, flown once after the agents were frozen (its README).
FRESH_TASKS_FILE = TASKS_FILE.parent / "results" / "as_built" / "fresh_test" / "tasks.toml"
ROLES = ("train", "validation", "test")
_KEYS = {"role", "description", "seeds", "env", "controller", "scenarios", "held_out", "vary"}
VARIED = {"plant": PLANTS, "actuator": ("paper", "fins", "realistic")}  # what `vary` may vary
MAX_SEED = 2**32 - 1  # numpy's SeedSequence accepts any, SB3 and Gymnasium pass 32-bit seeds


@dataclass(frozen=True)
class TaskSet:
    """A named set of episodes: env keyword arguments on every seed of ``seeds``."""

    name: str
    role: str
    description: str
    seeds: range
    env: dict[str, Any] = field(default_factory=dict)
    controller: dict[str, Any] = field(default_factory=dict)  # a scenario's controller kwargs
    held_out: str | None = None  # the training set whose distribution this one lies outside
    vary: tuple[str, tuple[str, ...]] | None = None  # (env key, its values): module doc

    def episodes(self) -> list[tuple[dict[str, Any], int]]:
        """(env keyword arguments, seed) of every episode of the set: with ``vary``, every seed
        once per value, value by value."""
        if self.vary is None:
            return [(dict(self.env), seed) for seed in self.seeds]
        key, values = self.vary
        return [({**self.env, key: value}, seed) for value in values for seed in self.seeds]

    def eval_env(self) -> dict[str, Any]:
        """The env keyword arguments a training run's validation passes on: ``env``, with the
        varied key's list of values when the set varies one
        (`benchmarks.training.evaluation.variant_groups` splits them again)."""
        if self.vary is None:
            return dict(self.env)
        key, values = self.vary
        return {**self.env, key: list(values)}


def _seeds(where: str, spec: Any) -> range:
    if not isinstance(spec, Mapping) or set(spec) != {"first", "count"}:
        raise ValueError(f"{where}: seeds must be {{ first = <int>, count = <int> }}, got {spec!r}")
    first, count = spec["first"], spec["count"]
    for name, value in (("first", first), ("count", count)):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{where}: seeds.{name} must be an integer, got {value!r}")
    if first < 0 or count < 1 or first + count - 1 > MAX_SEED:
        raise ValueError(
            f"{where}: seeds must satisfy first >= 0, count >= 1 and first + count "
            f"- 1 <= {MAX_SEED}, got first = {first}, count = {count}"
        )
    return range(first, first + count)


def _check_env(where: str, env: dict[str, Any]) -> SimConfig:
    try:
        return config_from_kwargs(env)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def load_task_sets(
    path: Path = TASKS_FILE, scenarios_file: Path = SCENARIOS_FILE
) -> dict[str, TaskSet]:
    """Every task set of the file, validated (module docstring); scenario lists are expanded
    into one set per scenario named "scenario:<name>"."""
    raw = read_toml(path, "task file")
    sets: dict[str, TaskSet] = {}
    configs: dict[str, SimConfig] = {}
    scenarios = None
    for name, table in raw.items():
        where = f"{path.name}: task set {name!r}"
        if not isinstance(table, Mapping):
            raise ValueError(f"{where} must be a table")
        unknown = sorted(set(table) - _KEYS)
        if unknown:
            raise ValueError(f"{where} has unknown keys {unknown}; valid: {sorted(_KEYS)}")
        role = table.get("role")
        if role not in ROLES:
            raise ValueError(f"{where}: role must be one of {list(ROLES)}, got {role!r}")
        seeds = _seeds(where, table.get("seeds"))
        description = str(table.get("description", ""))
        held_out = table.get("held_out")
        if held_out is not None and role != "test":
            raise ValueError(f"{where}: only a test set can be held_out, this one is {role!r}")
        if "scenarios" in table:
            if role != "test" or {"env", "controller"} & set(table) or held_out is not None:
                raise ValueError(
                    f"{where}: scenarios belong to a test set without env/controller/held_out"
                )
            scenarios = scenarios if scenarios is not None else load_scenarios(scenarios_file)
            names = table["scenarios"]
            missing = [n for n in names if n not in scenarios]
            if missing:
                raise ValueError(f"{where}: unknown scenarios {missing}; valid: {list(scenarios)}")
            for n in names:
                key = f"scenario:{n}"
                sc = scenarios[n]
                configs[key] = _check_env(f"{where}, scenario {n!r}", sc.env)
                sets[key] = TaskSet(
                    key, role, sc.description, seeds, dict(sc.env), dict(sc.controller)
                )
            continue
        env = dict(table.get("env", {}))
        vehicle_beside(env, path)
        controller = table.get("controller", {})
        if not isinstance(controller, Mapping):
            raise ValueError(f"{where}: controller must be a table, got {controller!r}")
        vary = _vary(where, table.get("vary"), role, env, controller)
        checked = []
        if vary is not None:
            key, values = vary
            checked = [_check_env(f"{where}, {key} {v!r}", {**env, key: v}) for v in values]
        configs[name] = checked[0] if checked else _check_env(where, env)
        sets[name] = TaskSet(name, role, description, seeds, env, dict(controller), held_out, vary)
    _check_disjoint(path.name, sets)
    _check_held_out(path.name, sets, configs)
    return sets


def _vary(
    where: str, spec: Any, role: str, env: dict[str, Any], controller: Mapping[str, Any]
) -> tuple[str, tuple[str, ...]] | None:
    """A validation set's ``vary`` table: one key of `VARIED` (not also in ``env`` or the
    ``controller`` table) with two or more distinct values of its own."""
    if spec is None:
        return None
    if role != "validation":
        raise ValueError(f"{where}: only a validation set may vary, this one is {role!r}")
    if not isinstance(spec, Mapping) or len(spec) != 1 or next(iter(spec)) not in VARIED:
        raise ValueError(
            f"{where}: vary must be a table of one key of {sorted(VARIED)}, got {spec!r}"
        )
    ((key, values),) = spec.items()
    if key in env or key in controller:
        raise ValueError(f"{where}: give vary.{key} or {key} in env/controller, not both")
    if (
        not isinstance(values, list)
        or len(values) < 2
        or len(set(values)) != len(values)
        or not all(v in VARIED[key] for v in values)
    ):
        raise ValueError(
            f"{where}: vary.{key} must list two or more distinct values of "
            f"{list(VARIED[key])}, got {values!r}"
        )
    return key, tuple(values)


def _check_disjoint(file: str, sets: dict[str, TaskSet]) -> None:
    """Training and validation seeds meet no test set's, nor each other's."""
    for a, b in combinations(sets.values(), 2):
        roles = {a.role, b.role}
        if roles == {"test"} or (roles == {"train"}):
            continue  # test sets may share seeds (different envs); so may training sets
        lo, hi = max(a.seeds.start, b.seeds.start), min(a.seeds.stop, b.seeds.stop)
        if lo < hi:
            raise ValueError(
                f"{file}: {a.role} set {a.name!r} and {b.role} set {b.name!r} "
                f"share seeds [{lo}, {hi}): test episodes would leak"
            )


def _check_held_out(file: str, sets: dict[str, TaskSet], configs: dict[str, SimConfig]) -> None:
    for s in sets.values():
        if s.held_out is None:
            continue
        where = f"{file}: task set {s.name!r}"
        train = sets.get(s.held_out)
        if train is None or train.role != "train":
            raise ValueError(f"{where}: held_out must name a training set, got {s.held_out!r}")
        mine, theirs = configs[s.name].path, configs[train.name].path
        if not (isinstance(mine, PathDistribution) and isinstance(theirs, PathDistribution)):
            raise ValueError(f"{where}: held_out sets and their training set need random paths")
        common = overlaps(mine, theirs)
        if common:
            raise ValueError(
                f"{where} is marked held_out but the training set {train.name!r} can "
                f"draw its {', '.join(common)} paths"
            )


def task_set(name: str, path: Path = TASKS_FILE) -> TaskSet:
    """One task set by name; an unknown name raises ValueError listing the valid ones."""
    sets = load_task_sets(path)
    if name not in sets:
        raise ValueError(f"unknown task set {name!r}; valid: {sorted(sets)}")
    return sets[name]


def test_suite(path: Path = TASKS_FILE) -> list[TaskSet]:
    """Every test set, the benchmark scenarios included, in file order."""
    return [s for s in load_task_sets(path).values() if s.role == "test"]


test_suite.__test__ = False  # type: ignore[attr-defined]  # not a pytest test


@functools.cache
def test_seeds() -> frozenset[int]:
    """Every reset seed a test set of the catalog (`TASKS_FILE`) or of the fresh held-out
    episodes (`FRESH_TASKS_FILE`) flies: what validation, tuning and selection must not use."""
    seeds: set[int] = set()
    for path in (TASKS_FILE, FRESH_TASKS_FILE):
        if path.is_file():
            seeds.update(s for t in test_suite(path) for s in t.seeds)
    return frozenset(seeds)


test_seeds.__test__ = False  # type: ignore[attr-defined]  # not a pytest test
