"""The port-starboard mirror stage: a network averaged with its own mirror image.

The vehicle, its ocean and the task distribution are symmetric under the reflection y → −y
(docs/design.md §3.19): a laterally symmetric hull in a mirrored current flies the mirrored
path, and the best policy is mirror-equivariant, π(M_o·o) = M_a·π(o). A trained network is not:
a bias of its own leaves each seed with a steady lateral offset on the calm helix, of either
sign. The stage ``{"name": "mirror_symmetry"}`` flies

    π_sym(o) = ½·(π(o) + M_a·π(M_o·o)),

equivariant by construction, with M_o the observation's signs (`auv_gym.sim.observation.
mirror_signs`) and M_a = diag(1, 1, −1) on (X, M, N): an offset the network holds on one side it
also holds, mirrored, on the other, and the two cancel. It needs the network (two evaluations per
step, one batched call), so it wraps the network rather than its commands, and it acts after
training only: SB3 samples its training actions from the bare network. It presumes the plant is
symmetric too; the 6-DOF plant as built is not (its propeller's torque rolls the hull one way),
and there it costs the as-built agent (docs/design.md §3.19).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from auv_gym.sim.observation import mirror_signs

__all__ = ["ACTION_MIRROR", "MIRROR_STAGE", "MirroredNetwork", "mirrored"]

MIRROR_STAGE = "mirror_symmetry"
ACTION_MIRROR = np.array([1.0, 1.0, -1.0], dtype=np.float32)  # (X, M, N): the yaw moment flips


class MirroredNetwork:
    """``network`` (a Policy of the observation ``obs_names``) averaged with its mirror image
    (module doc). Every other attribute (metadata, path, ...) is the network's."""

    def __init__(self, network: Any, obs_names: Sequence[str], where: str) -> None:
        try:
            self.signs = mirror_signs(obs_names)
        except ValueError as error:
            raise ValueError(f"{where}: stage {MIRROR_STAGE}: {error}") from None
        space = getattr(network, "action_space", None)
        if space is not None and not np.isclose(space.low[2], -space.high[2]):
            raise ValueError(
                f"{where}: stage {MIRROR_STAGE}: the action box {space.low.tolist()} .. "
                f"{space.high.tolist()} is not symmetric in the yaw command, which it mirrors"
            )
        self.network = network

    def __getattr__(self, name: str) -> Any:
        if name == "network":  # not set yet (e.g. while unpickling): no recursion
            raise AttributeError(name)
        return getattr(self.network, name)

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """½·(π(o) + M_a·π(M_o·o)) for observations (d,) or (n, d): one call of the network on
        the 2n rows."""
        obs = np.asarray(observation, dtype=np.float32)
        single = obs.ndim == 1
        rows = obs.reshape(1, -1) if single else obs
        if rows.ndim != 2 or rows.shape[1] != self.signs.size:
            raise ValueError(
                f"observation must have shape ({self.signs.size},) or (n, {self.signs.size}), "
                f"got {obs.shape}"
            )
        n = rows.shape[0]
        starts = None if episode_start is None else np.tile(np.asarray(episode_start), 2)
        both, state = self.network.predict(
            np.concatenate([rows, rows * self.signs]), state, starts, deterministic
        )
        both = np.asarray(both, dtype=np.float32)
        action = np.float32(0.5) * (both[:n] + both[n:] * ACTION_MIRROR)
        return (action[0] if single else action), state

    def __repr__(self) -> str:
        return f"MirroredNetwork({self.network!r})"


def mirrored(
    network: Any, specs: Sequence[Mapping[str, Any]], obs_names: Sequence[str], where: str
) -> Any:
    """``network`` inside the mirror stage when the checked stage ``specs`` list it, else
    ``network`` itself."""
    if any(spec["name"] == MIRROR_STAGE for spec in specs):
        return MirroredNetwork(network, obs_names, where)
    return network
