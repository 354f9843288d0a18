r"""Residual policy: a classical base controller plus a learned, bounded correction
(docs/design.md §3.10).

Per control step k, with o_k the env's observation (`auv_gym.sim.observation`), b_k the base
controller's normalised action and a_{k−1} the previously applied action (0 at an episode's
first step):

    b_k  = base.predict(o_k, episode_start)                    exactly as the base runs alone
    c_k  = agent.predict([o_k, b_k, a_{k−1}])                  `residual_observation_names`
    a_k  = clip(b_k + β ⊙ clip(c_k, −1, 1), −1, 1)             β = `bound` per input (X, M, N)

or, with ``bound_below`` β⁻ (how far below its base a negative correction may take an input),
β ⊙ c where c ≥ 0 and β⁻ ⊙ c where c < 0: c = 0 is still the base, and the agent may push the
thrust up past the base's command by β but pull it down by β⁻ only (docs/design.md §3.10).
With ``brake_fin_margin`` m the thrust's reach below its base also depends on the situation:

    β⁻_X,k = β⁻_X · clip((1 − max(|b_M,k|, |b_N,k|)) / m, 0, 1)

whole while the base's fins have a margin m or more, none when either fin command is at its
limit: the agent may brake on a leg, not into a turn the fins can no longer make at a lower
speed (fin authority falls with u², docs/model.md §2.3).

With an envelope guard (``envelope_guard``, `controllers.envelope_guard`) the applied action is
the guard's view of it, a_k ← guard(a_k; θ, q, u of o_k), before it becomes a_{k−1}: the agent
cannot correct its base past the vehicle's pitch or surge limits, and what it sees as its previous
action is what the env received.

o_k is the env's observation of whatever kind the agent was trained on (`auv_gym.ObservationConfig`:
the paper's 15 values, 21 with b_k and a_{k−1}; or the preview of the path ahead and the error
integrals after them): the base reads the paper's 15 it always reads, the agent sees all of it.

With a learned filter (``filter_max`` α_max > 0) the agent returns six values (c_k, g_k) and
also chooses, per input and per step, how much of its previous action to keep:

    t_k  = clip(b_k + β ⊙ clip(c_k, −1, 1), −1, 1)
    α_k  = α_max · clip(g_k, 0, 1)                             α_k = 0 at an episode's first step
    a_k  = α_k ⊙ a_{k−1} + (1 − α_k) ⊙ t_k

a first-order low-pass (`controllers.lowpass`) whose coefficient the agent sets from the state:
smoothing is one output away instead of a function the network has to build from b_k and
a_{k−1} (docs/design.md §3.10). g_k ≡ 1, c_k ≡ 0 is `controllers.lowpass` at α = α_max.

β is a fraction of the actuator range in normalised units (1 = the full limit: 50 N for X,
10 N·m or the fin authority for M and N, docs/model.md §2.3), so |a_k − b_k| ≤ β for any agent
output without the filter, |a_k| ≤ 1 (the actuator saturation) with or without it (a convex
combination of two actions in range). A non-finite agent output is an error, never an action.
The default β = (0.25, 0.5, 0.5): under the paper's noise the FBSM's pitch and yaw commands
swing with a standard deviation of 0.6 and 0.45 (surge 0.03, measured over 4 episodes of
`fbsm_colos`), so halving that chattering needs a correction of half the range; surge needs
less.

The base controller gets every observation, `episode_start` flag and `deterministic` flag the
evaluation would give it alone, so its adaptive laws, filters and observers evolve exactly as
without the agent: with c ≡ 0 (and g ≤ 0) the residual policy reproduces its base bit for bit.

The training side (the wrapper's observation, the chattering charge and the other reward terms,
`benchmarks.training.residual`) records its settings, a superset of `ResidualSettings`, under
"residual" in the saved agent's `metadata.json`; `controllers.loader.load_policy` rebuilds a
`ResidualPolicy` from it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from auv_gym.sim.observation import (
    OBS_DIM,
    OBS_NAMES,
    ObservationConfig,
    vehicle_speed_bound,
)
from auv_gym.sim.task import REMUS_TOP_SPEED
from controllers.env_settings import policy_settings
from controllers.envelope_guard import (
    EnvelopeGuard,
    check_envelope_guard,
    check_guard_sign,
    guard_env_commands,
)
from controllers.registry import CLASSICAL, make_classical

__all__ = [
    "DEFAULT_BASE",
    "DEFAULT_BOUND",
    "DEFAULT_FILTER_MAX",
    "NO_STAGES",
    "RESIDUAL_FEATURES",
    "RESIDUAL_OBS_DIM",
    "RESIDUAL_OBS_NAMES",
    "ResidualPolicy",
    "ResidualSettings",
    "agent_action_dim",
    "agent_observation",
    "base_kwargs_for_env",
    "check_bound",
    "filter_coefficient",
    "make_residual",
    "reach_below",
    "residual_action",
    "residual_observation_bounds",
    "residual_observation_names",
]

DEFAULT_BASE = "fbsm_colos"  # the current-robust FBSM (controllers.PRESETS)
DEFAULT_BOUND = (0.25, 0.5, 0.5)  # β per input (X, M, N), normalised actuator units
MAX_FILTER = 0.99  # α_max ≤ 0.99: a time constant of at most 100 control steps
# Largest learned filter coefficient α_max; 0: no filter, the agent returns three corrections.
DEFAULT_FILTER_MAX = 0.0
RESIDUAL_FEATURES = ("base_X", "base_M", "base_N", "previous_X", "previous_M", "previous_N")
# The agent observation on the paper's env observation (21 values); other kinds:
# `residual_observation_names`.
RESIDUAL_OBS_NAMES: tuple[str, ...] = (*OBS_NAMES, *RESIDUAL_FEATURES)
RESIDUAL_OBS_DIM = len(RESIDUAL_OBS_NAMES)
# Why a residual agent's files or hyper-parameters may list no stages.
NO_STAGES = (
    "a residual agent takes no stages (its base is its own; its envelope guard is a residual "
    "setting: residual: {envelope_guard: ...})"
)
# Set by the env (the scenario; `controllers.env_settings`), never by the residual settings.
ENV_OWNED_BASE_KWARGS = ("actuator", "control_dt", "params", "actuator_params")


def check_bound(bound: Any, name: str = "bound") -> tuple[float, float, float]:
    """β (or β⁻, ``name``) as three floats in [0, 2] (2: the whole range [−1, 1]); ValueError
    naming the value."""
    try:
        values = tuple(float(b) for b in np.broadcast_to(np.asarray(bound, dtype=float), (3,)))
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be a number or three numbers (X, M, N) in [0, 2], got {bound!r}"
        ) from None
    if not all(math.isfinite(b) and 0.0 <= b <= 2.0 for b in values):
        raise ValueError(f"{name} must lie in [0, 2] for each of X, M, N, got {list(values)}")
    return values  # type: ignore[return-value]


def check_number(name: str, value: Any, low: float, high: float, unit: str = "") -> float:
    """``value`` as a float in [low, high]; ValueError naming ``name`` (bools are refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
        raise ValueError(f"{name} must be a number in [{low:g}, {high:g}]{unit}, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class ResidualSettings:
    """What makes an agent residual at inference: the base controller (a name of
    `controllers.CLASSICAL` and its keyword arguments other than the env-owned
    ``ENV_OWNED_BASE_KWARGS``: control period, vehicle, actuator model), β (and β⁻ where the
    reach below the base differs, ``bound_below``; None: β), the learned
    filter's largest coefficient α_max (0: none; docs/design.md §3.10) and the envelope guard
    of the applied action (None: none; a mapping of `EnvelopeGuard` fields or True in a file).
    The reward terms training adds are the training side's
    (`benchmarks.training.residual.ResidualTraining`, a subclass)."""

    base: str = DEFAULT_BASE
    bound: tuple[float, float, float] = DEFAULT_BOUND
    filter_max: float = DEFAULT_FILTER_MAX
    base_kwargs: dict[str, Any] = field(default_factory=dict)
    envelope_guard: EnvelopeGuard | None = None
    # β⁻: how far below its base a negative correction may take each input (None: β).
    bound_below: tuple[float, float, float] | None = None
    # m: the base fins' margin [normalised] below which the thrust's reach below its base
    # shrinks to none at the fins' limit (None: a constant reach; module doc).
    brake_fin_margin: float | None = None

    def __post_init__(self) -> None:
        if self.base not in CLASSICAL:
            raise ValueError(
                f"residual base {self.base!r} is not a classical controller; "
                f"valid: {list(CLASSICAL)}"
            )
        object.__setattr__(self, "bound", check_bound(self.bound))
        if self.bound_below is not None:
            below = check_bound(self.bound_below, "bound_below")
            object.__setattr__(self, "bound_below", below)
        if self.brake_fin_margin is not None:
            margin = check_number("brake_fin_margin", self.brake_fin_margin, 0.0, 1.0)
            if margin == 0.0:
                raise ValueError("brake_fin_margin must be > 0 (0 would divide by zero)")
            object.__setattr__(self, "brake_fin_margin", margin)
        filter_max = check_number(
            "filter_max", self.filter_max, 0.0, MAX_FILTER, " (1 would freeze the action)"
        )
        object.__setattr__(self, "filter_max", filter_max)
        if not isinstance(self.base_kwargs, Mapping):
            raise ValueError(f"base_kwargs must be a mapping, got {self.base_kwargs!r}")
        owned = sorted(set(self.base_kwargs) & set(ENV_OWNED_BASE_KWARGS))
        if owned:
            raise ValueError(f"base_kwargs must not set {owned}: the env (scenario) sets them")
        object.__setattr__(self, "base_kwargs", dict(self.base_kwargs))
        if self.envelope_guard is False:  # a file's "no guard"
            object.__setattr__(self, "envelope_guard", None)
        if self.envelope_guard is not None:
            guard = check_envelope_guard(self.envelope_guard, "residual")
            object.__setattr__(self, "envelope_guard", guard)

    @classmethod
    def from_dict(cls, data: Any, where: str = "residual", *, strict: bool = True) -> Any:
        """Settings from a YAML/JSON mapping whose keys are the fields (all optional; a missing
        one takes its default); ValueError naming ``where`` and the problem. ``strict=False``
        ignores other keys (a saved agent's record of how it was trained)."""
        if data is None or data is True:
            data = {}
        if not isinstance(data, Mapping):
            raise ValueError(f"{where} must be a mapping, got {data!r}")
        keys = [f.name for f in fields(cls)]
        unknown = sorted(set(data) - set(keys))
        if unknown and strict:
            raise ValueError(f"{where}: unknown keys {unknown}; valid: {sorted(keys)}")
        values = {k: data[k] for k in keys if k in data}
        if "base" in values:
            values["base"] = str(values["base"])
        values["base_kwargs"] = values.get("base_kwargs") or {}
        try:
            return cls(**values)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        """The JSON form recorded in an agent's metadata (the guard only when there is one, so
        an agent without it records what it always did)."""
        return self.with_optional(
            {
                "base": self.base,
                "bound": list(self.bound),
                "filter_max": self.filter_max,
                "base_kwargs": dict(self.base_kwargs),
            }
        )

    def with_optional(self, record: dict[str, Any]) -> dict[str, Any]:
        """``record`` with β⁻ under "bound_below", m under "brake_fin_margin" and the envelope
        guard's settings under "envelope_guard", each only if set (an agent without them records
        what it always did)."""
        if self.bound_below is not None:
            record["bound_below"] = list(self.bound_below)
        if self.brake_fin_margin is not None:
            record["brake_fin_margin"] = self.brake_fin_margin
        if self.envelope_guard is not None:
            record["envelope_guard"] = self.envelope_guard.to_dict()
        return record

    def inference(self) -> ResidualSettings:
        """The settings a `ResidualPolicy` needs (these, without any training terms)."""
        return ResidualSettings(
            self.base,
            self.bound,
            self.filter_max,
            self.base_kwargs,
            self.envelope_guard,
            self.bound_below,
            self.brake_fin_margin,
        )

    @property
    def action_dim(self) -> int:
        """Values per vehicle the agent returns: 3 corrections, 6 with the learned filter."""
        return agent_action_dim(self.filter_max)

    def make_base(self, **kwargs: Any) -> Any:
        """The base controller: `base_kwargs`, then ``kwargs`` (the scenario's ``actuator``,
        ``control_dt``, ...; they win). The envelope guard's pitch sign is checked against
        that actuator (`controllers.envelope_guard.check_guard_sign`)."""
        if self.envelope_guard is not None:
            check_guard_sign(self.envelope_guard, kwargs.get("actuator"), "residual")
        return make_classical(self.base, **{**self.base_kwargs, **kwargs})


def base_kwargs_for_env(env_kwargs: Any) -> dict[str, Any]:
    """The base controller's env-owned arguments for episodes of ``env_kwargs`` (keyword
    arguments, a `SimConfig` or an env: `controllers.env_settings.env_config`), those of any
    classical controller on that env (`controllers.env_settings.policy_settings`): its
    ``control_dt``, the vehicle record ``params`` and a fixed ``actuator`` with its
    ``actuator_params`` ("random" draws per episode, which a Policy cannot see: the base then
    keeps its default "paper", like any classical controller). Training, validation and the
    benchmark thus fly one base on the vehicle a recipe names."""
    return policy_settings(env_kwargs)


def residual_observation_names(observation: Any = None) -> tuple[str, ...]:
    """The agent's observation names: the env observation's (``observation``, any spec of
    `auv_gym.ObservationConfig.from_spec`; None: the paper's 15), then `RESIDUAL_FEATURES`."""
    return (*ObservationConfig.from_spec(observation).names, *RESIDUAL_FEATURES)


def residual_observation_bounds(
    max_surge: float = REMUS_TOP_SPEED,
    observation: Any = None,
    current_speed: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of the agent's observation: the env's bounds for a vehicle of top speed
    ``max_surge`` [m/s] (`AUVParams.max_surge`; REMUS 100's: `OBS_LOW`, `OBS_HIGH`), observation
    ``observation`` (None: the paper's) and currents up to ``current_speed`` [m/s], then ±1 for
    b and a_{k−1}."""
    config = ObservationConfig.from_spec(observation)
    low, high = config.bounds(current_speed, vehicle_speed_bound(max_surge))
    ones = np.ones(len(RESIDUAL_FEATURES), dtype=np.float32)
    return np.concatenate([low, -ones]), np.concatenate([high, ones])


def agent_observation(obs: np.ndarray, base_action: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """The agent's float32 observation (n, d + 6): env observation (n, d), base action, previous
    action."""
    return np.concatenate(
        [
            np.asarray(obs, np.float32),
            np.asarray(base_action, np.float32),
            np.asarray(previous, np.float32),
        ],
        axis=1,
    )


def agent_action_dim(filter_max: float) -> int:
    """Values per vehicle a residual agent returns: 3 (c), or 6 (c, g) with a learned filter."""
    return 6 if filter_max > 0.0 else 3


def residual_action(
    base_action: np.ndarray,
    correction: Any,
    bound: Sequence[float],
    filter_max: float = 0.0,
    previous: np.ndarray | None = None,
    started: np.ndarray | None = None,
    bound_below: Sequence[float] | None = None,
    *,
    brake_fin_margin: float | None = None,
) -> np.ndarray:
    """The applied action as float32 (n, 3) (module doc): a = clip(b + β ⊙ clip(c, −1, 1), −1, 1)
    (with ``bound_below`` β⁻ in place of β where c < 0, its thrust entry scaled by the base's
    fin margin with ``brake_fin_margin``, `reach_below`), then with ``filter_max`` α_max > 0
    (``correction`` (n, 6) = (c, g)) the learned low-pass a = α ⊙ a_prev + (1 − α) ⊙ a,
    α = α_max·clip(g, 0, 1), 0 on rows not ``started``.
    ValueError for an output of another shape or with NaN/inf (naming the first bad row)."""
    b = np.asarray(base_action, dtype=np.float64)
    try:
        c = np.asarray(correction, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"residual agent returned a non-numeric correction {correction!r:.80}"
        ) from None
    expected = (b.shape[0], agent_action_dim(filter_max))
    if c.shape != expected:
        raise ValueError(
            f"residual agent returned a correction of shape {c.shape}, expected {expected}"
        )
    finite = np.isfinite(c)
    if not finite.all():
        row = int(np.argwhere(~finite)[0][0])
        raise ValueError(
            f"residual agent returned a non-finite correction {c[row].tolist()} (row {row}): "
            "NaN/inf is an error, not an action"
        )
    reach = np.clip(c[:, :3], -1.0, 1.0)
    if bound_below is None and brake_fin_margin is None:
        step = np.asarray(bound) * reach
    else:
        below = reach_below(b, bound if bound_below is None else bound_below, brake_fin_margin)
        step = np.where(reach < 0.0, below, np.asarray(bound)) * reach
    target = np.clip(b + step, -1.0, 1.0)
    target = target.astype(np.float32)
    if filter_max == 0.0:
        return target
    if previous is None or started is None:
        raise ValueError("a learned filter needs the previous actions and the started flags")
    alpha = filter_coefficient(c[:, 3:], filter_max, started)
    # float32 throughout, as `controllers.lowpass`, so g ≡ 1 reproduces it bit for bit
    return (alpha * previous + (np.float32(1.0) - alpha) * target).astype(np.float32)


def reach_below(
    base_action: np.ndarray, bound_below: Sequence[float], brake_fin_margin: float | None
) -> np.ndarray:
    """β⁻ per row: (3,) as given without a fin margin; with ``brake_fin_margin`` m, (n, 3) whose
    thrust entry is β⁻_X · clip((1 − max(|b_M|, |b_N|)) / m, 0, 1) (module doc)."""
    below = np.asarray(bound_below, dtype=np.float64)
    if brake_fin_margin is None:
        return below
    fins = np.max(np.abs(base_action[:, 1:3]), axis=1)
    scale = np.clip((1.0 - fins) / brake_fin_margin, 0.0, 1.0)
    rows = np.repeat(below[None, :], base_action.shape[0], axis=0)
    rows[:, 0] *= scale
    return rows


def filter_coefficient(g: np.ndarray, filter_max: float, started: np.ndarray) -> np.ndarray:
    """α = α_max·clip(g, 0, 1) as float32 (n, 3), 0 on rows not ``started`` (no a_{k−1})."""
    alpha = np.float32(filter_max) * np.clip(np.asarray(g), 0.0, 1.0).astype(np.float32)
    alpha[~np.asarray(started, dtype=bool)] = 0.0
    return alpha


class ResidualPolicy:
    """Base controller + bounded agent correction (module doc); the Policy protocol
    (docs/design.md §3.6).

    Args:
        base: the base controller (any Policy; `controllers.make(name)` of a classical one).
        agent: a Policy of the residual observation (`residual_observation_names`: 21 values
            on the paper's env observation; its ``obs_dim``, where it has one, says how many)
            giving corrections in [−1, 1]³, or (c, g) ∈ [−1, 1]⁶ with a learned filter (e.g. the
            actor of a saved residual agent, `controllers.agent.AgentPolicy`).
        bound: β per input (X, M, N) in normalised actuator units, each in [0, 2]; β⁻, where
            it differs, comes with the ``settings`` (``bound_below``).
        settings: the `ResidualSettings` it was built from (recorded, optional; its
            ``filter_max`` α_max switches the learned filter on).

    State: a dict with the base's state ("base"), the previously applied actions
    ("previous", (n, 3) float32), the last correction actually applied ("correction",
    a − b) and filter coefficient ("filter", α, 0 without the filter). `diagnostics` forwards
    the base's and adds ``correction`` and, with the filter, ``filter_coefficient`` (n, 3).
    """

    name = "residual"

    def __init__(
        self,
        base: Any,
        agent: Any,
        bound: Any = DEFAULT_BOUND,
        settings: ResidualSettings | None = None,
    ) -> None:
        for role, policy in (("base", base), ("agent", agent)):
            if not callable(getattr(policy, "predict", None)):
                raise ValueError(
                    f"residual {role} must have predict(...), got {type(policy).__name__}"
                )
        self.base = base
        self.agent = agent
        self.bound = check_bound(bound)
        self.settings = settings
        self.filter_max = 0.0 if settings is None else settings.filter_max
        self.guard = None if settings is None else settings.envelope_guard
        self.bound_below = None if settings is None else settings.bound_below
        self.brake_fin_margin = None if settings is None else settings.brake_fin_margin
        self.action_dim = agent_action_dim(self.filter_max)
        self.metadata = dict(getattr(agent, "metadata", {}) or {})
        # The env observation's width [values]: what the agent sees less b_k and a_{k−1}.
        self.obs_dim = int(getattr(agent, "obs_dim", RESIDUAL_OBS_DIM)) - len(RESIDUAL_FEATURES)
        if self.obs_dim < OBS_DIM:
            raise ValueError(
                f"residual agent observes {self.obs_dim + len(RESIDUAL_FEATURES)} values; it "
                f"needs the env's {OBS_DIM} or more and the {len(RESIDUAL_FEATURES)} of "
                f"{list(RESIDUAL_FEATURES)}"
            )
        base_width = getattr(base, "observation_width", OBS_DIM)
        if self.obs_dim < base_width:
            raise ValueError(
                f"residual base {getattr(base, 'name', 'base')!r} reads {base_width} observation "
                f"values (the DVL's velocity over ground), the agent's env gives {self.obs_dim}: "
                "train and fly it on observation='preview'"
            )

    def init_state(self, n: int) -> dict[str, Any]:
        return {
            "base": None,
            "previous": np.zeros((n, 3), np.float32),
            "started": np.zeros(n, dtype=bool),
            "correction": np.zeros((n, 3), np.float32),
            "filter": np.zeros((n, 3), np.float32),
        }

    def predict(
        self,
        observation: np.ndarray,
        state: dict[str, Any] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Actions in [−1, 1] for a batch (n, d) or one (d,) env observation (d = `obs_dim`:
        15 for the paper's); see the module doc."""
        obs = np.asarray(observation)
        single = obs.ndim == 1
        dim = self.obs_dim
        if obs.ndim not in (1, 2) or obs.shape[-1] != dim:
            raise ValueError(f"observation must have shape (n, {dim}) or ({dim},), got {obs.shape}")
        batch = obs[None] if single else obs
        n = batch.shape[0]
        if state is None:
            state = self.init_state(n)
        elif state["previous"].shape[0] != n:
            raise ValueError(
                f"state is for {state['previous'].shape[0]} vehicles, observation for {n}"
            )
        # The base sees exactly what it would see alone (the caller's arrays, unchanged).
        base_action, state["base"] = self.base.predict(
            observation,
            state=state["base"],
            episode_start=episode_start,
            deterministic=deterministic,
        )
        base_action = np.asarray(base_action, np.float32).reshape(n, 3)
        if episode_start is not None:
            start = np.asarray(episode_start, dtype=bool).reshape(-1)
            state["previous"][start] = 0.0
            state["started"][start] = False
        features = agent_observation(batch, base_action, state["previous"])
        correction, _ = self.agent.predict(features, deterministic=deterministic)
        if np.size(correction) == self.action_dim * n:  # an agent may return (k,) for one row
            correction = np.reshape(correction, (n, self.action_dim))
        applied = residual_action(
            base_action,
            correction,
            self.bound,
            self.filter_max,
            state["previous"],
            state["started"],
            self.bound_below,
            brake_fin_margin=self.brake_fin_margin,
        )
        applied = guard_env_commands(applied, batch, self.guard)
        if self.filter_max > 0.0:
            g = np.asarray(correction, np.float64)[:, 3:]
            state["filter"][:] = filter_coefficient(g, self.filter_max, state["started"])
        state["previous"][:] = applied
        state["started"][:] = True
        state["correction"][:] = applied - base_action
        return (applied[0] if single else applied), state

    def diagnostics(self, state: dict[str, Any]) -> dict[str, np.ndarray]:
        """The base's diagnostics (if it has any), the applied correction a − b and, with a
        learned filter, its coefficient α ("filter_coefficient"), each (n, 3)."""
        hook = getattr(self.base, "diagnostics", None)
        out = dict(hook(state["base"])) if hook is not None else {}
        out["correction"] = state["correction"].astype(np.float64)
        if self.filter_max > 0.0:
            out["filter_coefficient"] = state["filter"].astype(np.float64)
        return out

    def __repr__(self) -> str:
        return f"ResidualPolicy(base={self.base!r}, agent={self.agent!r}, bound={self.bound})"


def make_residual(
    agent: Any,
    base: str | None = None,
    bound: Any = None,
    filter_max: float | None = None,
    envelope_guard: Any = None,
    bound_below: Any = None,
    brake_fin_margin: float | None = None,
    **base_kwargs: Any,
) -> ResidualPolicy:
    """A `ResidualPolicy` of the Policy ``agent`` (`residual_observation_names`): ``base`` (default
    "fbsm_colos") and ``base_kwargs`` (e.g. ``actuator``, ``control_dt``, gains) build the base
    controller; ``bound`` is β (X, M, N), ``bound_below`` β⁻ (None: β), ``brake_fin_margin`` m
    the fin margin that scales the thrust's β⁻ (None: constant); ``filter_max`` α_max > 0
    gives the learned filter (an agent of six outputs); ``envelope_guard`` (an `EnvelopeGuard`,
    a mapping of its fields or True) guards the applied action. A saved residual agent's
    directory: `controllers.loader`.
    """
    owned = {k: base_kwargs.pop(k) for k in ENV_OWNED_BASE_KWARGS if k in base_kwargs}
    settings = ResidualSettings(
        base=DEFAULT_BASE if base is None else base,
        bound=DEFAULT_BOUND if bound is None else bound,
        base_kwargs=base_kwargs,
        filter_max=DEFAULT_FILTER_MAX if filter_max is None else filter_max,
        envelope_guard=envelope_guard,
        bound_below=bound_below,
        brake_fin_margin=brake_fin_margin,
    )
    return ResidualPolicy(settings.make_base(**owned), agent, settings.bound, settings)
