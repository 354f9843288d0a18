"""A user-defined policy for the benchmark tests: heads for the virtual point with P-control."""

from __future__ import annotations

import numpy as np

from auv_gym import OBS_INDEX


class PursuitPolicy:
    """Proportional pursuit: surge to u_D, yaw and pitch to cancel the LOS errors."""

    name = "pursuit"

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        i = OBS_INDEX
        surge = 0.0324 + 0.5 * (obs[:, i["u_D"]] - obs[:, i["u"]])
        psi_d = -np.arctan(0.3 * obs[:, i["y_e"]])
        yaw = -2.0 * (obs[:, i["psi_error"]] - psi_d) - 3.0 * obs[:, i["r"]]
        theta_d = obs[:, i["theta_F"]] + np.arctan(0.3 * obs[:, i["z_e"]])
        pitch = -2.0 * (obs[:, i["theta"]] - theta_d) - 3.0 * obs[:, i["q"]]
        action = np.clip(np.column_stack([surge, pitch, yaw]), -1.0, 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), state


policy = PursuitPolicy()


def make_policy(**controller_kwargs):
    """A factory, as `module:attribute` may also name one."""
    return PursuitPolicy()
