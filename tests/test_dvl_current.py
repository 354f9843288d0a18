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
