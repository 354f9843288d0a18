"""The current read from the DVL (`controllers.alos`, 5; gain ``dvl_current``): the velocity over
ground of the agents' observation, given to the classical guidance in place of the observer."""

from __future__ import annotations

import numpy as np
import pytest

import controllers
from auv_gym import ENV_ID
from auv_gym.rollout import rollouts
from benchmarks.catalog.policies import policy_env
from controllers.gains import ControllerGains
from controllers.registry import reads_ground_velocity
from tests.test_current_guidance import body_current
from tests.test_env_settings import _ZeroAgent

DVL_PID = {"current_observer": 0.0, "dvl_current": 0.3, "speed_over_ground": True}
AS_BUILT = {"disturbance": "ocean", "actuator": "realistic", "sensors": "typical_kalman"}


def test_the_current_is_measured_from_the_first_step_where_the_observer_must_converge():
    """Helix, constant current with a vertical component, exact sensors: ĉ = R_Bᵀ v_c from the
    first sample (the observer starts from zero and needs 30 s to reach 1e-3 m/s)."""
    mean = (0.1, 0.25, 0.05)
    (tr,) = rollouts(
        controllers.make("pid_los", **DVL_PID),
        [0],
        path="helix",
        disturbance="none",
        current={"mean": mean},
        observation="preview",
        max_time=60.0,
    )
    error = np.abs(tr["current_hat"] - body_current(tr, mean)[:-1]).max(axis=1)
    assert error[0] < 1e-6  # ĉ(0) = m, the measured current itself (a float32 observation)
    # the filter turns with the body: measured 2.3e-3 m/s while turning in, 8e-4 after 30 s
    assert error.max() < 5e-3
    assert error[tr.t[:-1] >= 30.0].max() < 2e-3


def test_the_gains_take_one_source_of_the_current():
    with pytest.raises(ValueError, match="current_observer and dvl_current are two sources"):
        ControllerGains(current_observer=3.0, dvl_current=0.3)
    with pytest.raises(ValueError, match="dvl_current"):
        ControllerGains(dvl_current=-0.3)
    with pytest.raises(ValueError, match="needs current_observer > 0 or dvl_current > 0"):
        ControllerGains(speed_over_ground=True)
    assert ControllerGains(**DVL_PID).dvl_current == 0.3


def test_the_papers_observation_is_refused_by_name():
    pid = controllers.make("pid_as_built_dvl", actuator="realistic")
    assert pid.observation_width == 18
    with pytest.raises(ValueError, match=r"dvl_current .* d >= 18 .*observation='preview'"):
        pid.predict(np.zeros(15, dtype=np.float32))


def test_the_benchmark_flies_it_on_the_agents_observation():
    assert reads_ground_velocity("pid_as_built_dvl")
    assert reads_ground_velocity("pid_as_built", **DVL_PID)
    assert reads_ground_velocity("guarded", base="pid_as_built_dvl")
    assert not reads_ground_velocity("pid_as_built")
    assert not reads_ground_velocity("fbsm")
    assert not reads_ground_velocity("guarded", base="pid_as_built")
    assert policy_env("pid_as_built_dvl") == (ENV_ID, {"observation": "preview"})
    assert policy_env("pid_as_built_climb_soft_pitch") == (ENV_ID, {})


def test_the_agents_observation_leaves_the_other_controllers_bit_for_bit():
    """The agents' observation begins with the paper's 15 entries: a controller that reads only
    those flies the same trajectory on either (as built: navigation, waves, propeller)."""
    pid = controllers.make("pid_as_built_climb_soft_pitch", actuator="realistic")
    paper, preview = (
        rollouts(pid, [3], max_time=30.0, observation=kind, **AS_BUILT)[0]
        for kind in ("paper", "preview")
    )
    for name in ("x_e", "y_e", "z_e", "u", "theta", "psi"):
        np.testing.assert_array_equal(paper[name], preview[name])


def test_it_holds_the_true_along_track_error_that_the_observer_cannot():
    """As built, under the plant's virtual-point law: the observer reads u_p at the estimated
    x_e while the point moves with the true one, and the navigation's jumps as a current; the
    DVL's current has neither, and the speed over ground it gives holds the true x_e."""
    kwargs = {**AS_BUILT, "max_time": 150.0, "observation": "preview"}
    names = ("pid_as_built_climb_soft_pitch", "pid_as_built_dvl")
    observer, dvl = (
        rollouts(controllers.make(name, actuator="realistic"), [0], **kwargs)[0] for name in names
    )
    late = observer.t >= 50.0
    rms = [float(np.sqrt(np.mean(tr["x_e"][late] ** 2))) for tr in (observer, dvl)]
    assert rms[1] < 0.5 * rms[0], rms


def test_a_fresh_state_at_speed_starts_the_filter_at_rest():
    """ĉ(0) = m is an initialisation, not a turn of the estimate: its jump from the zeroed
    memory must not enter the command filter as a rate of the crab angle (at 1.5 m/s in a
    0.3 m/s cross current it read as 6 rad/s and doubled the first heading correction)."""
    from auv_gym.sim.observation import OBS_INDEX
    from controllers.los import FILTER_DIM, LOOP_DIM, loop_errors

    pid = controllers.make("pid_as_built_dvl", actuator="realistic")
    o = np.zeros(18)
    o[OBS_INDEX["u"]], o[OBS_INDEX["u_D"]], o[OBS_INDEX["u_p"]] = 1.5, 1.0, 1.0
    # on the path (y_e = 0): the ALOS trims, which adapt on y_e, add no rate of their own
    o[15], o[16] = 1.5, 0.3  # over ground: the cross current on top of the surge
    filt, out = np.zeros(FILTER_DIM), np.zeros(LOOP_DIM)
    loop_errors(o, pid._g, filt, False, out)
    assert filt[3] == 0.0  # the heading correction's rate: the filter starts at rest
    first = filt[2]
    loop_errors(o, pid._g, filt, True, out)
    assert abs(filt[2] - first) < 1e-3  # and stays near c_y while nothing changes


def test_a_narrow_env_or_residual_is_refused_before_it_flies():
    with pytest.raises(ValueError, match=r"pid_as_built_dvl reads 18 .* env gives 15"):
        controllers.make("pid_as_built_dvl", env={"actuator": "realistic"})
    pid = controllers.make(
        "pid_as_built_dvl", env={"actuator": "realistic", "observation": "preview"}
    )
    assert pid.env_kwargs == {"observation": "preview"}  # `rollouts` flies it on that observation
    guarded = controllers.make("guarded", base="pid_as_built_dvl", actuator="realistic")
    assert (guarded.observation_width, guarded.env_kwargs) == (18, {"observation": "preview"})
    (tr,) = rollouts(pid, [0], max_time=5.0, **AS_BUILT)  # no observation given: it carries one
    assert tr["current_hat"].shape == (100, 3)  # 5 s at the control period of 0.05 s
    with pytest.raises(ValueError, match=r"residual base .* reads 18 .* gives 15"):
        controllers.make(
            "residual", agent=_ZeroAgent(), base="pid_as_built_dvl", actuator="realistic"
        )
