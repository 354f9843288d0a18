"""An agent's stages: what happens to its commands between its network and the env, in order.

A trained network is rarely the whole agent. Its metadata lists the stages its commands pass,
outermost last, each a mapping with its ``name`` and settings::

    "stages": [
        {"name": "envelope_guard", "pitch_soft_deg": 35.0, ...},   # controllers.envelope_guard
        {"name": "mirror_symmetry"},                              # controllers.mirror
        {"name": "actuator_allocation", "commands": "paper"},     # controllers.actuator_allocation
    ]

The allocation may carry ``"observation_factors": {"y_e": 0.25, ...}``: on the actuator it
allocates to, the network sees those entries scaled (a gain schedule by actuator,
docs/design.md §3.21). It may also carry ``"surge_floor_soft"`` and ``"surge_floor_hard"``
[m/s]: on that actuator the envelope guard gets this low-speed floor (fins lose their moments
with u², a directly commanded τ does not; docs/design.md §3.22).

The mirror is the one stage that wraps the network instead of its commands (it evaluates the
network twice), so it may be listed anywhere and acts first.

One implementation applies them everywhere: `StagedPolicy` around the network at inference
(`controllers.loader.load_policy`), and `benchmarks.training.stages.StagedActions` around the
vector env in training (the same `Stage` objects, the same arithmetic). A stage may also rewrite
what the network observes (the allocation feeds back the command the actuator delivered) and
keep a per-vehicle memory between steps, reset at each episode start.

A stage reads its inputs from the raw observation by name (θ, q, u for the guard; u, v, w and
the previous action for the allocation); `build_stages` checks that the agent's observation
holds them before anything runs. Unknown stage names, settings or an order other than
`STAGE_ORDER` are one-line errors naming the file and what exists.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from auv_gym.support.validation import real
from controllers.actuator_allocation import (
    ALLOCATED_ACTUATORS,
    COMMANDED_ACTUATOR,
    PREV_ACTION_NAMES,
    VELOCITY_INPUTS,
    Allocation,
    check_actuator_allocation,
)
from controllers.envelope_guard import GUARD_INPUTS, check_envelope_guard, guard_commands
from controllers.mirror import MIRROR_STAGE, MirroredNetwork

__all__ = [
    "STAGE_ORDER",
    "AllocationStage",
    "DrawnAllocationStage",
    "GuardStage",
    "ObservationFactors",
    "PipelineState",
    "Stage",
    "StagedPolicy",
    "apply_stages",
    "build_stages",
    "check_allocated_floor",
    "check_observation_factors",
    "check_stage_specs",
    "observe_stages",
]

# The order the commands pass them; the mirror wraps the network itself (`controllers.mirror`).
STAGE_ORDER = (MIRROR_STAGE, "envelope_guard", "actuator_allocation")
# The guard's low-speed floor an allocation may set on its actuator [m/s] (docs/design.md §3.22).
FLOOR_KEYS = ("surge_floor_soft", "surge_floor_hard")
ALLOCATION_KEYS = ("commands", "observation_factors", *FLOOR_KEYS)


class Stage:
    """One stage: `observe` may rewrite the network's observation, `act` transforms the commands
    (normalised, (n, 3)); `memory` is the stage's per-vehicle state (None: stateless)."""

    name = ""

    def start(self, n: int) -> Any:
        """The memory of ``n`` vehicles at their episodes' start."""
        return None

    def restart(self, memory: Any, rows: np.ndarray) -> None:
        """Reset the memory of the vehicles ``rows`` (bool, (n,)) whose episode starts."""

    def observe(self, observation: np.ndarray, memory: Any) -> np.ndarray:
        """What the network sees, from the raw observations (n, d)."""
        return observation

    def act(
        self, commands: np.ndarray, observation: np.ndarray, memory: Any
    ) -> tuple[np.ndarray, Any]:
        """The commands (n, 3) after this stage, and its memory after the step."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        """The stage as metadata.json lists it."""
        raise NotImplementedError


class GuardStage(Stage):
    """The envelope guard (`controllers.envelope_guard`): pitch and surge commands ramped away
    near the vehicle's limits, read from θ, q, u of the observation. Stateless."""

    name = "envelope_guard"

    def __init__(self, settings: Any, obs_names: Sequence[str], where: str) -> None:
        self.guard = check_envelope_guard(settings, where)
        missing = [n for n in GUARD_INPUTS if n not in obs_names]
        if missing:
            raise ValueError(
                f"{where}: envelope_guard reads {list(GUARD_INPUTS)} from the agent's "
                f"observation, which lacks {missing}"
            )
        self.index = tuple(list(obs_names).index(n) for n in GUARD_INPUTS)

    def act(
        self, commands: np.ndarray, observation: np.ndarray, memory: Any
    ) -> tuple[np.ndarray, Any]:
        return guard_commands(commands, observation, self.index, self.guard), memory

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, **self.guard.to_dict()}


@dataclass(frozen=True)
class ObservationFactors:
    """Entries of the observation the network sees multiplied by fixed factors on an allocated
    actuator: a gain schedule by actuator. ``index`` their positions in the layout, ``values``
    the factors (> 0), ``names`` as the metadata lists them."""

    names: tuple[str, ...]
    index: np.ndarray
    values: np.ndarray

    @classmethod
    def of(cls, factors: Mapping[str, float], obs_names: Sequence[str], where: str):
        """The factors of checked ``factors`` (`check_observation_factors`) for an agent
        observing ``obs_names``, or a one-line error naming the entries it lacks."""
        names = list(obs_names)
        missing = sorted(set(factors) - set(names))
        if missing:
            raise ValueError(
                f"{where}: actuator_allocation's observation_factors name {missing}, which the "
                "agent's observation lacks"
            )
        # the stages read these from what the network sees: scaled, they would fly other states
        read = sorted(set(factors) & {*VELOCITY_INPUTS, *PREV_ACTION_NAMES, *GUARD_INPUTS})
        if read:
            raise ValueError(
                f"{where}: actuator_allocation's observation_factors cannot scale {read}, which "
                "the stages read"
            )
        keys = tuple(factors)
        return cls(
            keys,
            np.array([names.index(k) for k in keys], dtype=np.intp),
            np.array([factors[k] for k in keys], dtype=np.float32),
        )

    def apply(self, observation: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """``observation`` (float32, (d,) or (n, d)) with the entries scaled, in place: every
        row, or the ``rows`` (bool, (n,)) given."""
        if rows is None:
            observation[..., self.index] *= self.values
        elif rows.any():
            observation[np.ix_(rows, self.index)] *= self.values
        return observation

    def removed(self, observation: np.ndarray) -> np.ndarray:
        """A float64 copy of scaled observations (n, d) with the scaling undone."""
        unscaled = np.array(observation, dtype=np.float64, copy=True)
        unscaled[..., self.index] /= self.values
        return unscaled

    def to_dict(self) -> dict[str, float]:
        return {name: float(v) for name, v in zip(self.names, self.values, strict=True)}


def check_observation_factors(value: Any, where: str) -> dict[str, float]:
    """``observation_factors`` of an ``actuator_allocation`` stage: a non-empty mapping of
    observation entries to finite factors > 0, or a one-line error naming ``where``."""
    if not isinstance(value, Mapping) or not value:
        raise ValueError(
            f"{where}: observation_factors must be a non-empty mapping {{entry: factor}}, "
            f"got {value!r}"
        )
    checked = {}
    for name, factor in value.items():
        ok = isinstance(factor, int | float) and not isinstance(factor, bool)
        if not isinstance(name, str) or not ok or not math.isfinite(factor) or factor <= 0:
            raise ValueError(
                f"{where}: observation_factors[{name!r}] must be a finite number > 0, "
                f"got {factor!r}"
            )
        checked[name] = float(factor)
    return checked


class AllocationStage(Stage):
    """The actuator allocation (`controllers.actuator_allocation`): the agent's normalised τ on
    the paper's actuator flown on the env's fins or propeller and fins; the memory is each
    vehicle's delivered command, fed back in the previous-action entries. With ``factors``
    the network also sees some entries scaled on this actuator (e.g. the path errors at the
    coarser scales a fin-limited vehicle can hold: docs/design.md §3.21)."""

    name = "actuator_allocation"

    def __init__(
        self,
        allocation: Allocation,
        factors: ObservationFactors | None = None,
        floor: Mapping[str, float] | None = None,
    ) -> None:
        self.allocation = allocation
        self.factors = factors
        self.floor = dict(floor or {})  # recorded here, applied by the guard stage

    def start(self, n: int) -> np.ndarray:
        return np.zeros((n, 3), dtype=np.float32)

    def restart(self, memory: np.ndarray, rows: np.ndarray) -> None:
        memory[rows] = 0.0

    def observe(self, observation: np.ndarray, memory: np.ndarray) -> np.ndarray:
        obs = np.array(observation, dtype=np.float32, copy=True)
        obs[:, self.allocation.previous_index] = memory
        return obs if self.factors is None else self.factors.apply(obs)

    def act(
        self, commands: np.ndarray, observation: np.ndarray, memory: Any
    ) -> tuple[np.ndarray, Any]:
        return self.allocation.allocate(commands, observation)

    def to_dict(self) -> dict[str, Any]:
        factors = {} if self.factors is None else {"observation_factors": self.factors.to_dict()}
        return {"name": self.name, "commands": COMMANDED_ACTUATOR, **factors, **self.floor}


class DrawnAllocationStage(AllocationStage):
    """The actuator allocation in training on an env that draws each episode's actuator
    (``actuator="random"``: the paper's or the fins): the rows whose episode drew the fins are
    allocated as `AllocationStage` allocates them, the others pass unchanged (the allocation is
    the identity on the paper's actuator), so that every vehicle meets the commands the exported
    agent will give on its actuator. Training only: the wrapper tells it each episode's draw
    (`set_drawn`; `benchmarks.training.stages.StagedActions`). The memory is (n, 4): the
    delivered command, then 1.0 on the allocated rows."""

    def start(self, n: int) -> np.ndarray:
        return np.zeros((n, 4), dtype=np.float32)

    def restart(self, memory: np.ndarray, rows: np.ndarray) -> None:
        memory[rows, :3] = 0.0

    def set_drawn(self, memory: np.ndarray, rows: np.ndarray, actuators: Sequence[str]) -> None:
        """Record the actuators drawn by the vehicles ``rows`` (bool, (n,)) whose episodes start:
        ``actuators`` holds every vehicle's (n,), "paper" or an allocated one."""
        drawn = np.asarray(actuators, dtype=object)
        unknown = sorted(set(drawn[rows]) - {COMMANDED_ACTUATOR, self.allocation.actuator})
        if unknown:
            raise ValueError(
                f"actuator_allocation in training allocates to {self.allocation.actuator!r} "
                f"and passes {COMMANDED_ACTUATOR!r}; the env drew {unknown}"
            )
        memory[rows, 3] = (drawn[rows] == self.allocation.actuator).astype(np.float32)

    def observe(self, observation: np.ndarray, memory: np.ndarray) -> np.ndarray:
        obs = np.array(observation, dtype=np.float32, copy=True)
        allocated = memory[:, 3] > 0.5
        obs[np.ix_(allocated, self.allocation.previous_index)] = memory[allocated, :3]
        return obs if self.factors is None else self.factors.apply(obs, allocated)

    def act(
        self, commands: np.ndarray, observation: np.ndarray, memory: Any
    ) -> tuple[np.ndarray, Any]:
        out = np.array(commands, dtype=np.float32, copy=True)
        allocated = memory[:, 3] > 0.5
        if allocated.any():
            out[allocated], memory[allocated, :3] = self.allocation.allocate(
                out[allocated], observation[allocated]
            )
        return out, memory


def check_allocated_floor(value: Mapping[str, Any], where: str) -> dict[str, float]:
    """The surge floor an ``actuator_allocation`` stage gives the guard on its actuator: both of
    ``surge_floor_soft`` > ``surge_floor_hard`` >= 0 [m/s] or neither ({}); a one-line error
    naming ``where`` otherwise (the guard's own checks follow where the guard is known)."""
    if not value:
        return {}
    missing = [k for k in FLOOR_KEYS if k not in value]
    if missing:
        raise ValueError(
            f"{where}: the surge floor needs both {list(FLOOR_KEYS)}, missing {missing}"
        )
    soft = real(
        f"{where}.surge_floor_soft", value["surge_floor_soft"], 0.0, 10.0, low_open=True, unit="m/s"
    )
    hard = real(f"{where}.surge_floor_hard", value["surge_floor_hard"], 0.0, 10.0, unit="m/s")
    if not hard < soft:
        raise ValueError(
            f"{where}: surge_floor_hard must lie below surge_floor_soft, got {hard:g} and "
            f"{soft:g} m/s"
        )
    return {"surge_floor_soft": soft, "surge_floor_hard": hard}


def _floored_guard(
    guard: Mapping[str, Any], allocation: Mapping[str, Any], where: str
) -> dict[str, Any]:
    """The guard's settings (a stage spec) with the allocation's surge floor in place of its own
    (checked as a guard: the floor must lie below the guard's surge_soft)."""
    settings = {k: v for k, v in guard.items() if k != "name"}
    settings |= {k: allocation[k] for k in FLOOR_KEYS}
    return check_envelope_guard(settings, where).to_dict()


def check_stage_specs(specs: Any, where: str) -> tuple[dict[str, Any], ...]:
    """The stage list of an agent's metadata or a training config, checked: a list of mappings
    with a known ``name`` (`STAGE_ORDER`) and valid settings, each at most once, in that order.
    A one-line ValueError naming ``where`` otherwise."""
    if specs is None:
        return ()
    if not isinstance(specs, Sequence) or isinstance(specs, str):
        raise ValueError(f"{where}: stages must be a list of {{name: ...}} mappings, got {specs!r}")
    checked = []
    for spec in specs:
        if isinstance(spec, str):
            spec = {"name": spec}
        if not isinstance(spec, Mapping) or "name" not in spec:
            raise ValueError(f"{where}: each stage is a mapping with a 'name', got {spec!r}")
        name = spec["name"]
        if name not in STAGE_ORDER:
            raise ValueError(f"{where}: unknown stage {name!r}; stages: {list(STAGE_ORDER)}")
        settings = {k: v for k, v in spec.items() if k != "name"}
        if name == "envelope_guard":
            settings = check_envelope_guard(settings, f"{where}: stage {name}").to_dict()
        elif name == MIRROR_STAGE:
            if settings:
                raise ValueError(f"{where}: stage {name} takes no settings, got {sorted(settings)}")
        else:
            unknown = sorted(set(settings) - set(ALLOCATION_KEYS))
            if unknown:
                raise ValueError(
                    f"{where}: stage {name} has unknown keys {unknown}; valid: "
                    f"{list(ALLOCATION_KEYS)}"
                )
            check_actuator_allocation(
                settings.get("commands", COMMANDED_ACTUATOR), f"{where}: stage {name}"
            )
            factors = settings.get("observation_factors")
            floor = {k: settings[k] for k in FLOOR_KEYS if k in settings}
            settings = {"commands": COMMANDED_ACTUATOR}
            if factors is not None:
                settings["observation_factors"] = check_observation_factors(
                    factors, f"{where}: stage {name}"
                )
            settings |= check_allocated_floor(floor, f"{where}: stage {name}")
        checked.append({"name": name, **settings})
    names = [s["name"] for s in checked]
    # the mirror wraps the network, wherever it is listed (an export adds it after the stages
    # the agent trained inside); the command stages keep their order
    passed = [name for name in names if name != MIRROR_STAGE]
    if len(set(names)) != len(names) or passed != sorted(passed, key=STAGE_ORDER.index):
        raise ValueError(
            f"{where}: stages {names} must each appear once, in the order {list(STAGE_ORDER)}"
        )
    floored = any(FLOOR_KEYS[0] in spec for spec in checked if spec["name"] != "envelope_guard")
    if floored:
        guard = next((spec for spec in checked if spec["name"] == "envelope_guard"), None)
        if guard is None:
            raise ValueError(
                f"{where}: actuator_allocation's surge floor is the envelope guard's on its "
                "actuator; add an envelope_guard stage before it"
            )
        allocation = next(spec for spec in checked if spec["name"] == "actuator_allocation")
        _floored_guard(guard, allocation, f"{where}: stage actuator_allocation")
    return tuple(checked)


def build_stages(
    specs: Sequence[Mapping[str, Any]],
    obs_names: Sequence[str],
    settings: Mapping[str, Any] | None = None,
    where: str = "stages",
    drawn: str | None = None,
) -> list[Stage]:
    """The `Stage` objects of checked ``specs`` (`check_stage_specs`) for an agent observing
    ``obs_names``, on the plant of ``settings`` (`controllers.env_settings.policy_settings`:
    ``actuator``, ``params``, ``actuator_params``). The allocation is the identity on the
    actuator the agent commands (the paper's) and on one drawn per episode ("random"), which
    tells a deployed agent nothing: it is left out there. In training on such an env,
    ``drawn`` names the allocated actuator the episodes may draw ("fins"): the allocation is
    then a `DrawnAllocationStage` to it, told each episode's draw by the training wrapper.
    The mirror stage is not among them: it wraps the network (`controllers.mirror.mirrored`)."""
    settings = settings or {}
    allocation_spec = next((s for s in specs if s["name"] == "actuator_allocation"), {})
    floored = FLOOR_KEYS[0] in allocation_spec
    if floored and drawn is not None:
        raise ValueError(
            f"{where}: actuator_allocation's surge floor guards a deployed agent on its actuator; "
            "in training on a drawn actuator it is not applied (list it in the schedule's export "
            "stages)"
        )
    allocated = drawn is None and settings.get("actuator") in ALLOCATED_ACTUATORS
    stages: list[Stage] = []
    for spec in specs:
        if spec["name"] == MIRROR_STAGE:
            continue
        if spec["name"] == "envelope_guard":
            if floored and allocated:  # the allocated actuator's floor (docs/design.md §3.22)
                settings_of_guard = _floored_guard(spec, allocation_spec, where)
            else:
                settings_of_guard = {k: v for k, v in spec.items() if k != "name"}
            stages.append(GuardStage(settings_of_guard, obs_names, where))
        else:
            factors = spec.get("observation_factors")
            if factors is not None:
                factors = ObservationFactors.of(factors, obs_names, where)
            if drawn is not None:
                allocation = Allocation(
                    obs_names, drawn, settings.get("params"), settings.get("actuator_params"), where
                )
                stages.append(DrawnAllocationStage(allocation, factors))
            elif allocated:
                allocation = Allocation(
                    obs_names,
                    settings["actuator"],
                    settings.get("params"),
                    settings.get("actuator_params"),
                    where,
                )
                floor = {k: allocation_spec[k] for k in FLOOR_KEYS if k in allocation_spec}
                stages.append(AllocationStage(allocation, factors, floor))
    return stages


@dataclass
class PipelineState:
    """The network's recurrent state and each stage's memory, for one batch of vehicles."""

    inner: Any
    memories: list[Any]
    n: int


def observe_stages(
    stages: Sequence[Stage], observation: np.ndarray, memories: Sequence[Any]
) -> np.ndarray:
    """What the network sees: the raw observations (n, d) through every stage's `observe`."""
    for stage, memory in zip(stages, memories, strict=True):
        observation = stage.observe(observation, memory)
    return observation


def apply_stages(
    stages: Sequence[Stage], commands: np.ndarray, observation: np.ndarray, memories: list[Any]
) -> np.ndarray:
    """The network's commands (n, 3) through every stage in order; ``memories`` is updated in
    place. ``observation`` is what the network saw."""
    for k, stage in enumerate(stages):
        commands, memories[k] = stage.act(commands, observation, memories[k])
    return commands


class StagedPolicy:
    """A network (a Policy of its observation, e.g. `controllers.agent.AgentPolicy`) with its
    stages: the Policy of the whole agent. Every other attribute (metadata, path, ...) is the
    network's."""

    def __init__(self, actor: Any, stages: Sequence[Stage]) -> None:
        self.actor = actor
        self.stages = list(stages)
        self.path = getattr(actor, "path", None)

    def __getattr__(self, name: str) -> Any:  # metadata, label, num_threads... of the network
        if name == "actor":  # not set yet (e.g. while unpickling): no recursion
            raise AttributeError(name)
        return getattr(self.actor, name)

    def predict(
        self,
        observation: np.ndarray,
        state: PipelineState | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, PipelineState]:
        """The agent's commands (float32, (3,) or (n, 3)) for raw observations (d,) or (n, d)."""
        single = np.ndim(observation) == 1
        obs = np.atleast_2d(observation)
        n = obs.shape[0]
        if state is None or state.n != n:
            state = PipelineState(None, [stage.start(n) for stage in self.stages], n)
        if episode_start is not None:
            rows = np.asarray(episode_start, dtype=bool).reshape(n)
            for stage, memory in zip(self.stages, state.memories, strict=True):
                stage.restart(memory, rows)
        seen = observe_stages(self.stages, obs, state.memories)
        commands, inner = self.actor.predict(
            seen[0] if single else seen, state.inner, episode_start, deterministic
        )
        out = apply_stages(self.stages, np.atleast_2d(commands), seen, state.memories)
        state.inner = inner
        return (out[0] if single else out), state

    def __repr__(self) -> str:
        mirror = [MIRROR_STAGE] if isinstance(self.actor, MirroredNetwork) else []
        names = [*mirror, *(stage.name for stage in self.stages)]
        return f"StagedPolicy(path={self.path!r}, stages={names})"
