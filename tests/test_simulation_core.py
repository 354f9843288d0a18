"""The one simulation core: records instead of loose arrays, options compiled in only when used.

The loop itself is checked bit for bit against committed results (`benchmarks.checks.
reproduction`, tests/test_reproduction*.py) and against Fossen's code (tests/test_six_dof_plant.py);
here: what each configuration hands the kernels, and that the structure stays open.
"""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import numpy as np
import pytest

from auv_gym.sim import SimConfig, Simulator, period, plants, simulator
from auv_gym.sim import fleet as fleet_module

CORE = Path(simulator.__file__).parent
_NO_COST = {"depth": 0.0, "speed": 0.0, "pitch": 0.0}  # the safety cost is on by default


def _sim(**kwargs) -> Simulator:
    # The serial kernel, which the set-up compiles; the threaded one is the integration tier's.
    return Simulator(SimConfig.from_kwargs(**kwargs), n=2, parallel=False)


def _off(sim: Simulator) -> set[str]:
    off = {name for name, value in sim.fleet._asdict().items() if value is None}
    return off | ({"cost"} if sim.outputs.cost is None else set())


@pytest.mark.parametrize(
    ("kwargs", "expected_off"),
    [
        ({}, {"roll", "hull", "guidance"}),
        ({"actuator": "realistic", "disturbance": "ocean"}, {"roll", "hull", "guidance"}),
        ({"safety_cost": _NO_COST}, {"roll", "hull", "cost", "guidance"}),
        ({"plant": "6dof"}, {"guidance"}),
        ({"plant": "6dof", "safety_cost": _NO_COST}, {"cost", "guidance"}),
        # the sensor model alone keeps the plant's law; the guidance computer is an array
        ({"sensors": "typical_kalman"}, {"roll", "hull", "guidance"}),
        ({"sensors": {"preset": "typical", "virtual_point": "estimate"}}, {"roll", "hull"}),
    ],
)
def test_the_plant_and_an_unused_safety_cost_are_chosen_by_type(kwargs, expected_off) -> None:
    sim = _sim(**kwargs)
    assert _off(sim) == expected_off
    assert sim.six_dof == (kwargs.get("plant") == "6dof")


def test_the_records_are_the_simulators_own_arrays() -> None:
    """The kernels write through the records into the arrays `snapshot` and the envs read."""
    sim = _sim(actuator="realistic", plant="6dof")
    for name, array in sim.fleet._asdict().items():
        # no sensor model: no guidance computer (`tests/test_guidance_computer.py` has one)
        own = {"actuators": sim.actuator_state, "guidance": None}.get(
            name, getattr(sim, name, None)
        )
        assert array is own, name
    assert sim.outputs.obs is sim.obs and sim.episodes.cfgs is sim._cfg
    sim.reset_rows([0, 1], [np.random.default_rng(s) for s in (0, 1)])
    before = sim.actuator_state.copy()
    sim.step(np.full((2, 3), 0.5))
    assert not np.array_equal(sim.actuator_state, before)  # the propeller spun up in place
    assert np.all(sim.roll != 0.0)  # the 6-DOF rolled under the propeller's torque


def test_a_safety_cost_is_scored_where_configured() -> None:
    costly = _sim(safety_cost={"speed_limit": 0.1})
    costly.reset_rows([0, 1], [np.random.default_rng(s) for s in (0, 1)])
    for _ in range(20):  # full thrust for 2 s: past 0.1 m/s
        costly.step(np.tile([1.0, 0.0, 0.0], (2, 1)))
    assert np.all(costly.state[:, 5] > 0.1) and np.all(costly.cost > 0.0)  # the speed term
    # Zero weights: no cost array in the kernel, and the simulator's stays 0.
    assert _sim(safety_cost={**_NO_COST, "speed_limit": 0.1}).outputs.cost is None


def test_the_step_kernels_take_four_records_and_no_core_function_more_than_ten() -> None:
    for kernel in (simulator._step_one, simulator._step_all):
        assert list(inspect.signature(kernel.py_func).parameters) == [
            "fleet",
            "actions",
            "table",
            "out",
        ]
    for record in (fleet_module.Fleet, fleet_module.EpisodeTable, fleet_module.StepOutputs):
        assert len(record._fields) <= 10, record
    wide = []
    for path in (CORE / "simulator.py", CORE / "period.py", CORE / "plants.py", CORE / "fleet.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and len(node.args.args) > 12:
                wide.append(f"{path.name}:{node.name}")
    assert wide == []


def test_one_period_loop_serves_both_plants() -> None:
    """The plant hooks have a 5-DOF and a 6-DOF side each; the loop is written once."""
    source = inspect.getsource(period)
    assert source.count("for k in range(n_sub)") == 1
    assert not (CORE / "six_dof_integrator.py").exists()
    for hook in plants.__all__:
        if hook.islower():
            assert f"{hook}(" in source, hook


@pytest.mark.integration  # compiles the threaded kernels (about 1.5 min on 2 cores)
@pytest.mark.parametrize(
    "kwargs",
    [{}, {"actuator": "realistic", "disturbance": "ocean"}, {"plant": "6dof"}],
    ids=["paper", "as_built_ocean", "6dof"],
)
def test_the_threaded_kernel_equals_the_serial_one_bit_for_bit(kwargs) -> None:
    """Every array a step writes, after 15 steps of random commands in the box."""
    sims = [Simulator(SimConfig.from_kwargs(**kwargs), n=3, parallel=p) for p in (False, True)]
    commands = np.random.default_rng(7).uniform(-1.0, 1.0, (15, 3, 3))
    for sim in sims:
        sim.reset_rows([0, 1, 2], [np.random.default_rng(s) for s in (0, 1, 2)])
        for action in commands:
            sim.step(action)
    serial, threaded = (sim.snapshot()["arrays"] for sim in sims)
    for name, array in serial.items():
        np.testing.assert_array_equal(threaded[name], array, err_msg=name)
    assert np.all(sims[0].step_index == 15 * sims[0].config.substeps)
    assert np.all(sims[0].cost >= 0.0) and np.all(sims[0].reward != 0.0)
