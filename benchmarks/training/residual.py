"""Training settings of a residual agent (docs/design.md §3.10): the inference settings
(`controllers.residual.ResidualSettings`: base, β, α_max, base gains) plus the reward terms the
training wrapper adds (`benchmarks.training.residual_env`) and the chattering weight of the
validation score. A hyper-parameter file's ``residual`` section is read into `ResidualTraining`;
the saved agent's metadata records its `to_dict`, from which the loader takes what it needs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.residual import ResidualSettings, check_number

__all__ = [
    "DEFAULT_PRECISION_SCALE",
    "DEFAULT_PRECISION_WEIGHT",
    "DEFAULT_SELECTION_CHATTERING",
    "DEFAULT_TV_WEIGHT",
    "PRECISION_AXES",
    "PRIVILEGED_INFO_KEYS",
    "PRIVILEGED_NAMES",
    "ResidualTraining",
    "observed_error_columns",
    "privileged_extension",
    "privileged_names",
]

# Chattering charge per unit of total variation of the applied normalised action per step
# (docs/design.md §3.10): FBSM alone (TV ≈ 0.87 per step under the paper's noise) pays ≈ 0.22
# per step, about 5 % of what following the path earns.
DEFAULT_TV_WEIGHT = 0.25
MAX_TV_WEIGHT = 1e3
# Precision bonus w_P·exp(−(d/d_P)²) of training (docs/design.md §3.10): the env's tracking bonus
# has d_0 = 1 m and is flat where FBSM already is (d ≈ 0.07 m), so without it smoothing looks free.
# Weight 0: the reward of the first residual agents.
DEFAULT_PRECISION_WEIGHT = 0.0
DEFAULT_PRECISION_SCALE = 0.1  # [m] d_P
# The error d of the precision bonus: "xyz" the distance to the virtual point; "yz" its part
# across the path, √(y_e² + z_e²), for a vehicle whose along-track error is cheap to win (the
# as-built residual's: docs/results.md, "The residual on both plants: ten seeds").
PRECISION_AXES = ("xyz", "yz")
# A privileged critic's extra inputs (`benchmarks.training.privileged`): the true path errors
# the reward is charged on [m], and the keys of the env's info that report them.
PRIVILEGED_NAMES = ("true_x_e", "true_y_e", "true_z_e")
PRIVILEGED_INFO_KEYS = ("x_e", "y_e", "z_e")


def observed_error_columns(obs_names: Sequence[str]) -> list[int]:
    """The columns of the observed x_e, y_e, z_e among ``obs_names``: the entries whose bounds
    and initial statistics a privileged critic's true errors take."""
    names = list(obs_names)
    return [names.index(key) for key in PRIVILEGED_INFO_KEYS]


def privileged_names(obs_names: Sequence[str]) -> list[str]:
    """A privileged critic's input names: ``obs_names`` followed by `PRIVILEGED_NAMES`."""
    return [*obs_names, *PRIVILEGED_NAMES]


def privileged_extension(values: np.ndarray, obs_names: Sequence[str]) -> np.ndarray:
    """``values`` per observation entry (along the last axis: bounds, means, variances) followed
    by those of the observed x_e, y_e, z_e again: where a privileged critic's true errors start."""
    values = np.asarray(values)
    return np.concatenate([values, values[..., observed_error_columns(obs_names)]], axis=-1)


# Selection score rms_distance + λ·chattering [m]; λ [m·s] = 0: rms distance alone.
DEFAULT_SELECTION_CHATTERING = 0.0


@dataclass(frozen=True)
class ResidualTraining(ResidualSettings):
    """`ResidualSettings` plus the reward terms training adds (chattering charge w_TV,
    precision bonus w_P with scale d_P [m]) and the chattering weight λ [m·s] of the
    validation score."""

    tv_weight: float = DEFAULT_TV_WEIGHT
    precision_weight: float = DEFAULT_PRECISION_WEIGHT
    precision_scale: float = DEFAULT_PRECISION_SCALE
    selection_chattering: float = DEFAULT_SELECTION_CHATTERING
    precision_axes: str = PRECISION_AXES[0]
    # the critic also reads the true path errors (`benchmarks.training.privileged`)
    privileged_critic: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        for name, low, high, unit in (
            ("tv_weight", 0.0, MAX_TV_WEIGHT, ""),
            ("precision_weight", 0.0, MAX_TV_WEIGHT, ""),
            ("precision_scale", 1e-3, 10.0, " m"),
            ("selection_chattering", 0.0, 1.0, " m·s"),
        ):
            object.__setattr__(self, name, check_number(name, getattr(self, name), low, high, unit))
        if not isinstance(self.privileged_critic, bool):
            raise ValueError(
                f"privileged_critic must be true or false, got {self.privileged_critic!r}"
            )
        if self.precision_axes not in PRECISION_AXES:
            raise ValueError(
                f"precision_axes must be one of {list(PRECISION_AXES)}, got {self.precision_axes!r}"
            )

    def to_dict(self) -> dict[str, Any]:
        """The JSON form recorded in an agent's metadata (key order of the shipped agents;
        ``precision_axes`` only when not the distance, so they record what they always did)."""
        record = self.with_optional(
            {
                "base": self.base,
                "bound": list(self.bound),
                "tv_weight": self.tv_weight,
                "precision_weight": self.precision_weight,
                "precision_scale": self.precision_scale,
                "selection_chattering": self.selection_chattering,
                "filter_max": self.filter_max,
                "base_kwargs": dict(self.base_kwargs),
            }
        )
        if self.precision_axes != PRECISION_AXES[0]:
            record["precision_axes"] = self.precision_axes
        if self.privileged_critic:
            record["privileged_critic"] = True
        return record
