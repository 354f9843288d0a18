"""Named benchmark scenarios (`benchmarks/scenarios.toml`): env and controller keyword arguments.

An env table takes every `AUVPath3D-v0` argument, including a waypoint path
(``path = [[0, 0, 5], [40, 10, 8], ...]``), a random-path table (``path = { families =
["helix"], radius = [10, 13] }``) and vehicle parameters by name or scale factor
(``params = { m = 32.0, scale = { X_uu = 1.2 } }``); each is validated when the file is loaded.
A scenario's ``vehicle`` (a shipped vehicle's name or a vehicle file, docs/vehicles.md) is the
env's ``vehicle`` argument; the REMUS 100 when absent. A relative vehicle file (``vehicle =
"my_auv.toml"``, or in the env table) lies beside the scenario file, as an ensemble's members lie
beside its ensemble.json: the file works from any folder.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from auv_gym.support.files import read_toml
from benchmarks.arguments import comma_names

__all__ = ["SCENARIOS_FILE", "Scenario", "load_scenarios", "select", "vehicle_beside"]

SCENARIOS_FILE = Path(__file__).resolve().parents[1] / "scenarios.toml"


@dataclass(frozen=True)
class Scenario:
    """A named, documented set of env keyword arguments (and controller keyword arguments)."""

    name: str
    description: str
    env: dict[str, Any] = field(default_factory=dict)
    controller: dict[str, Any] = field(default_factory=dict)


def vehicle_beside(env: dict[str, Any], file: str | Path) -> None:
    """A relative vehicle file of an ``env`` table (``vehicle = "my_auv.toml"``) read from the
    TOML ``file`` that holds it lies beside that file, so it works from any folder; an absolute
    path and a shipped name are kept."""
    vehicle = env.get("vehicle")
    if isinstance(vehicle, str) and vehicle.endswith(".toml"):  # a file (`load_vehicle`)
        env["vehicle"] = str(Path(file).parent / vehicle)


def load_scenarios(path: Path = SCENARIOS_FILE) -> dict[str, Scenario]:
    """Scenarios from a TOML file: one table per scenario with description, vehicle, env and
    controller."""
    raw = read_toml(path, "scenario file")
    scenarios = {}
    if not raw:
        raise ValueError(f"{path}: no scenarios")
    for name, table in raw.items():
        if not isinstance(table, dict):
            raise ValueError(f"{path}: scenario {name!r} must be a table, got {table!r}")
        unknown = set(table) - {"description", "vehicle", "env", "controller"}
        if unknown:
            raise ValueError(f"{path}: scenario {name!r} has unknown keys {sorted(unknown)}")
        for key in ("env", "controller"):
            if not isinstance(table.get(key, {}), dict):
                raise ValueError(f"{path}: scenario {name!r}: {key} must be a table")
        if not isinstance(table.get("description", ""), str):
            raise ValueError(
                f"{path}: scenario {name!r}: description must be text, got "
                f"{table['description']!r:.40}"
            )
        env = dict(table.get("env", {}))
        if "vehicle" in table:  # the vehicle flown: a shipped name or a vehicle file
            if "vehicle" in env:
                raise ValueError(f"{path}: scenario {name!r}: vehicle given twice (and in env)")
            env["vehicle"] = table["vehicle"]
        vehicle_beside(env, path)
        scenarios[name] = Scenario(
            name, table.get("description", ""), env, dict(table.get("controller", {}))
        )
        _check_env(path, name, scenarios[name].env)
    return scenarios


def _check_env(path: Path, name: str, env: dict[str, Any]) -> None:
    """The env arguments build (paths, waypoint lists, `params` by name or scale factor): a bad
    one raises ValueError naming the file, the scenario and the argument."""
    from auv_gym.sim.config import config_from_kwargs

    try:
        config_from_kwargs(env)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{path}: scenario {name!r}: {exc}") from None


def select(names: str, available: Sequence[str], what: str) -> list[str]:
    """Comma-separated names ("all" for every one), validated against the available ones:
    ValueError for an unknown, empty or repeated name."""
    chosen = list(available) if names.strip() == "all" else comma_names(names, f"--{what}s")
    unknown = [n for n in chosen if n not in available]
    if unknown:
        raise ValueError(f"unknown {what} {unknown}; valid: {list(available)}")
    return chosen
