"""A vehicle is a data file: the shipped REMUS 100 file is today's vehicle bit for bit, a user's
file flies without code, and a bad file is one line naming the file and the field."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the env ids)
import controllers
from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollouts
from auv_gym.sim.config import SimConfig
from auv_gym.vehicle import (
    SENSOR_PRESETS,
    ActuatorParams,
    AUVParams,
    Vehicle,
    VehicleFileError,
    load_vehicle,
    shipped_vehicles,
)
from auv_gym.vehicle.record import VEHICLE_DIRECTORY, check_mass_matrix
from auv_gym.vehicle.remus6dof import SixDofVehicle

REMUS_FILE = VEHICLE_DIRECTORY / "remus100.toml"


def remus_layout() -> dict:
    return tomllib.loads(REMUS_FILE.read_text())


def write_toml(path: Path, data: dict) -> Path:
    """A minimal TOML writer for the vehicle layout (tables, arrays of tables, scalars)."""

    def value(v) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, float) and math.isinf(v):
            return "inf" if v > 0 else "-inf"
        if isinstance(v, float) and math.isnan(v):
            return "nan"
        return repr(v)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for name, table in data.items():
        if not isinstance(table, dict):
            continue
        lines.append(f"[{name}]")
        lines += [f"{k} = {value(v)}" for k, v in table.items() if not isinstance(v, list | dict)]
        lines += [
            f"{k} = {value(v)}"
            for k, v in table.items()
            if isinstance(v, list) and not (v and isinstance(v[0], dict))
        ]
        for key, items in table.items():
            if isinstance(items, list) and items and isinstance(items[0], dict):
                for item in items:
                    lines.append(f"[[{name}.{key}]]")
                    lines += [f"{k} = {value(v)}" for k, v in item.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_shipped_remus100_file_is_the_default_vehicle_bit_for_bit() -> None:
    assert "remus100" in shipped_vehicles()
    vehicle = load_vehicle("remus100")
    assert vehicle.hull_5dof == AUVParams()
    assert vehicle.actuators == ActuatorParams()
    assert vehicle.hull_6dof == SixDofVehicle()
    assert vehicle.sensors == SENSOR_PRESETS["typical"]
    assert len(vehicle.fins) == 4
    assert vehicle.hull_5dof.to_vector().tobytes() == AUVParams().to_vector().tobytes()
    for plant, actuator in (("5dof", "paper"), ("5dof", "realistic"), ("6dof", "realistic")):
        default = SimConfig.from_kwargs(plant=plant, actuator=actuator)
        named = SimConfig.from_kwargs(plant=plant, actuator=actuator, vehicle="remus100")
        from_file = SimConfig.from_kwargs(plant=plant, actuator=actuator, vehicle=REMUS_FILE)
        for config in (named, from_file):  # every field but the path (a new object each)
            assert dataclasses.replace(config, path=default.path) == default
        assert default.packed().tobytes() == from_file.packed().tobytes()
        assert named.vehicle == "remus100"


def test_a_named_vehicle_flies_the_same_episode_as_the_default() -> None:
    fbsm = controllers.make("fbsm")
    (default,) = rollouts(fbsm, [3], max_time=20.0)
    (named,) = rollouts(fbsm, [3], max_time=20.0, vehicle=str(REMUS_FILE))
    assert default.samples.keys() == named.samples.keys()
    for key, values in default.samples.items():
        assert np.array_equal(values, named.samples[key]), key


def test_params_on_a_vehicle_replace_its_fields() -> None:
    layout = remus_layout()
    layout["model_5dof"].update(m=33.0, W=33.0 * 9.81, B=33.0 * 9.81)  # [kg, N, N]
    layout["name"] = "heavier"
    config = SimConfig.from_kwargs(vehicle=layout, params={"I_y": 4.0})
    assert (config.params.m, config.params.I_y, config.vehicle) == (33.0, 4.0, "heavier")
    assert SimConfig.from_kwargs(sensors="vehicle").sensors == SENSOR_PRESETS["typical"]


def scaled_remus(factor: float) -> dict:
    """REMUS 100 scaled geometrically by ``factor`` in length: each coefficient by the power of
    the length in its unit (kg: 3, kg/m: 2, kg·m: 4, kg·m²: 5), the fins' area by 2 and position
    by 1, the moment limits by 4 (the thrust limit kept)."""
    powers = {"m": 3, "W": 3, "B": 3, "I_y": 5, "I_z": 5, "z_g": 1, "z_b": 1, "X_udot": 3}
    powers |= dict.fromkeys(["Y_vdot", "Z_wdot", "X_vr", "X_wq", "Y_ur", "Z_uq"], 3)
    powers |= dict.fromkeys(["M_uw", "M_ww", "N_uv", "N_vv", "fin_moment_coeff"], 3)
    powers |= dict.fromkeys(["M_qdot", "N_rdot", "M_qq", "N_rr"], 5)
    powers |= dict.fromkeys(["X_uu", "X_vv", "X_ww", "Y_uv", "Y_vv", "Z_uw", "Z_ww"], 2)
    powers |= dict.fromkeys(["X_qq", "X_rr", "M_uq", "N_ur", "M_max", "N_max"], 4)
    powers["X_max"] = 0
    layout = remus_layout()
    layout["name"] = "remus_scaled"
    model = layout["model_5dof"]
    assert set(model) == set(powers)  # every coefficient has its power
    for name, power in powers.items():
        model[name] *= factor**power
    for fin in layout["actuators"]["fins"]:
        fin["area"] *= factor**2
        fin["x"] *= factor
    hull = layout["model_6dof"]
    hull["length"] *= factor
    hull["diameter"] *= factor
    hull["r_bg"] = [factor * c for c in hull["r_bg"]]
    return layout


def test_a_users_vehicle_file_flies_with_pid_los_without_code(tmp_path: Path) -> None:
    path = write_toml(tmp_path / "remus_scaled.toml", scaled_remus(1.2))
    vehicle = load_vehicle(path)
    assert vehicle.name == "remus_scaled"
    assert vehicle.hull_5dof.m == pytest.approx(30.48 * 1.2**3)
    assert vehicle.hull_6dof.length == pytest.approx(1.92)
    env = gym.make("AUVPath3D-v0", vehicle=path)
    pid = controllers.make("pid_los", env=env)
    assert pid.params == vehicle.hull_5dof  # the controller reads the vehicle from the env
    env.close()
    (episode,) = rollouts(pid, [0], max_time=200.0, vehicle=str(path))
    metrics = compute_metrics(episode)
    assert episode.termination_reason == "time_limit"
    assert metrics["rms_distance"] < 0.2  # [m] after the approach: 0.045 (REMUS 100: 0.087)


@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda d: d["model_5dof"].pop("X_uu"), "[model_5dof] X_uu: missing"),
        (lambda d: d["model_5dof"].update(X_uuu=1.0), "[model_5dof] X_uuu: unknown field"),
        (lambda d: d["model_5dof"].update(X_uu=math.nan), "[model_5dof] X_uu: must be finite"),
        (lambda d: d["model_5dof"].update(m=-1.0), "AUVParams.m must be positive"),
        (lambda d: d["model_5dof"].update(I_y="3"), "[model_5dof] I_y: must be a number"),
        (
            lambda d: d["model_5dof"].update(B=306.0),  # Prestero's buoyant REMUS [N]
            "[model_5dof] B: 306 N must equal W = 299 N: the 5-DOF form has no (W − B) force",
        ),
        (
            lambda d: d["model_5dof"].update(m=33.0),  # [kg], W left at 299 N
            "[model_5dof] W: 299 N is not m·g = 33 kg × 9.81 m/s² ([model_6dof] gravity) = 323.7",
        ),
        (
            lambda d: d["model_5dof"].update(m=1e30, W=9.81e30, B=9.81e30),
            "[model_5dof] m: 1e+30 kg is 3.22e+28× the 31.03 kg of water the [model_6dof] hull",
        ),
        (
            lambda d: d["model_5dof"].update(m=30480.0, W=299010.0, B=299010.0),  # g, not kg
            "[model_5dof] m: 30480 kg is 982× the 31.03 kg",
        ),
        (
            lambda d: d["model_5dof"].update(z_g=-0.05),  # [m] above the centre of buoyancy
            "[model_5dof] z_g: -0.05 m must lie below z_b = 0 m (z_g > z_b, z down)",
        ),
        (
            lambda d: d["model_5dof"].update(fin_moment_coeff=0.0),
            "[model_5dof] fin_moment_coeff: 0 kg/rad is not the stern planes' |x|·½ρAC_L = 6.15",
        ),
        (
            lambda d: [fin.update(area=0.0133) for fin in d["actuators"]["fins"][2:]],
            "fin_moment_coeff: 6.15 kg/rad is not the rudders' |x|·½ρAC_L = 12.3 kg/rad",
        ),
        (
            lambda d: d["actuators"].update(water_density=1.2),  # [kg/m³] air
            "[model_6dof] water_density: 1026 kg/m³ differs from [actuators] water_density = 1.2",
        ),
        (
            lambda d: d["actuators"]["fins"][0].update(x=-50.0),
            "'stern_starboard' x: -50 m lies off the 1.6-m hull of [model_6dof]",
        ),
        (
            lambda d: d["model_5dof"].update(M_qdot=3.449),  # [kg m²/rad] a sign lost
            "[model_5dof] M_qdot: 3.449 must be ≤ 0: a submerged hull's added mass adds",
        ),
        (lambda d: d["limits"].pop("max_surge"), "[limits] max_surge: missing"),
        (lambda d: d["limits"].update(max_surge=0.0), "[limits] max_surge: must be positive"),
        (lambda d: d["model_5dof"].pop("N_max"), "[model_5dof] N_max: missing"),
        (
            lambda d: d["actuators"]["fins"][0].update(induced_drag=0.5),
            "'stern_port' induced_drag: 1 differs from fin 'stern_starboard''s 0.5",
        ),
        (
            lambda d: d["actuators"]["fins"][0].update(radius=-0.1),
            "'stern_starboard' radius: must be non-negative",
        ),
        (lambda d: d["actuators"].update(kt_0=-1.0), "[actuators]"),
        (
            lambda d: d["actuators"].update(kt_max=-5.0),
            "[actuators]: ActuatorParams.kt_max = -5 must be in (0, kt_0 = 0.4566]",
        ),
        (lambda d: d["model_6dof"].update(diameter=-0.2), "[model_6dof]"),
        (lambda d: d["model_6dof"].update(r_bg=[0.0, 0.0]), "[model_6dof] r_bg: must be a list"),
        (lambda d: d.update(format=2), "format: must be 1"),
        (lambda d: d.pop("name"), "name: missing"),
        (lambda d: d.update(colour="red"), "colour: unknown field"),
        (lambda d: d["sensors"].update(preset="perfect"), "[sensors] preset"),
        (
            lambda d: d["actuators"]["fins"][0].update(area=0.0),
            "'stern_starboard' area: must be positive",
        ),
        (lambda d: d["actuators"]["fins"][0].pop("x"), "#1 x: missing"),
        (
            lambda d: d["actuators"]["fins"][2].update(axis_roll=0.7),
            "'rudder_top' axis_roll: 0.7 rad is neither horizontal",
        ),
        (
            lambda d: d["actuators"].update(fins=d["actuators"]["fins"][:2]),
            "no fin can produce a yaw moment",
        ),
        (
            lambda d: [fin.update(x=0.0) for fin in d["actuators"]["fins"][:2]],
            "no fin can produce a pitch moment",
        ),
        (
            lambda d: d["actuators"]["fins"][1].update(lift_slope=1.0),
            "'stern_port' lift_slope: 1 differs",
        ),
        (
            lambda d: d["actuators"]["fins"][3].update(rate_max=2.0),
            "'rudder_bottom' rate_max: 2 differs",
        ),
        (lambda d: d["actuators"].pop("rpm_max"), "[actuators] rpm_max: missing"),
    ],
)
def test_a_bad_vehicle_file_is_one_line_naming_the_file_and_field(
    tmp_path: Path, edit, field: str
) -> None:
    layout = remus_layout()
    edit(layout)
    path = write_toml(tmp_path / "bad.toml", layout)
    with pytest.raises(VehicleFileError) as error:
        gym.make("AUVPath3D-v0", vehicle=path)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    assert field in message


def test_fins_whose_roll_moments_do_not_cancel_are_refused_by_the_env(tmp_path: Path) -> None:
    """Was: one stern plane off the axis flew as a pair without its roll moment."""
    layout = remus_layout()
    for fin in layout["actuators"]["fins"]:
        fin["radius"] = 0.1  # [m] off the axis, as a real fin
    assert load_vehicle(layout).pairs_problem == ""  # four in a cross: the moments cancel
    del layout["actuators"]["fins"][1]  # the port stern plane
    path = write_toml(tmp_path / "three_fins.toml", layout)
    with pytest.raises(VehicleFileError) as error:
        gym.make("AUVPath3D-v0", vehicle=path)
    assert str(error.value) == (
        f"{path}: [[actuators.fins]] 'stern_starboard': the stern planes' roll moments do not "
        "cancel (Σ A·r·cos φ = 0.000665 m³): the coupled pairs have no roll moment; give each "
        "fin an opposite one of equal area, or put them on the axis (radius 0)"
    )


def test_surge_coriolis_without_a_5dof_model_is_refused(tmp_path: Path) -> None:
    layout = tomllib.loads((VEHICLE_DIRECTORY / "torpedo.toml").read_text())
    layout["surge_coriolis"] = False
    with pytest.raises(VehicleFileError, match=r"surge_coriolis: sets a term of \[model_5dof\]"):
        load_vehicle(layout)


def test_a_vehicle_files_sensors_and_top_speed_are_named_with_the_file(tmp_path: Path) -> None:
    layout = remus_layout()
    layout["sensors"] = {"fix_interval": 0.07}  # [s] the other fields: SensorConfig's
    layout["limits"]["max_surge"] = 0.8  # [m/s] below the paper's u_D = 1 m/s
    path = write_toml(tmp_path / "slow.toml", layout)
    with pytest.raises(ValueError) as error:
        SimConfig.from_kwargs(vehicle=path, sensors="vehicle")
    assert str(error.value).startswith(f"{path}: [sensors] sensors fix_interval = 0.07 s must be")
    with pytest.raises(ValueError) as error:
        SimConfig.from_kwargs(vehicle=path, surge_limit="vehicle")
    assert f"is the vehicle's top speed ({path}: [limits] max_surge = 0.8 m/s)" in str(error.value)


def test_plant_params_give_the_derived_5dof_record_of_the_hull_flown() -> None:
    """Was: the torpedo's derived record (what the PID's gains and the limits come from) kept
    the file's 1.6-m hull while the 6-DOF plant flew the plant_params' 3-m one."""
    record = load_vehicle("torpedo").hull_6dof.record()
    record.update(length=3.0, diameter=0.3)  # [m]
    kwargs = {"vehicle": "torpedo", "plant": "6dof", "actuator": "realistic"}
    config = SimConfig.from_kwargs(**kwargs, plant_params=record)
    assert config.params.m == config.plant_params.mass_kg == pytest.approx(145.047, abs=1e-3)
    assert SimConfig.from_kwargs(**kwargs).params.m == pytest.approx(31.029, abs=1e-3)


def test_a_mass_matrix_that_is_not_positive_definite_is_refused() -> None:
    mass = SixDofVehicle().mass.copy()
    check_mass_matrix(mass, lambda field, problem: VehicleFileError(f"f.toml: {field}: {problem}"))
    mass[3, 3] = -0.01  # [kg m²] a roll inertia below zero
    with pytest.raises(VehicleFileError, match=r"f.toml: \[model_6dof\]: mass matrix .* not pos"):
        check_mass_matrix(mass, lambda f, p: VehicleFileError(f"f.toml: {f}: {p}"))


def test_unknown_names_and_unreadable_files_are_one_line(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"'torpedo9' is not a shipped vehicle \['remus100'"):
        SimConfig.from_kwargs(vehicle="torpedo9")
    with pytest.raises(VehicleFileError, match="cannot be read"):
        load_vehicle(tmp_path / "absent.toml")
    corrupt = tmp_path / "corrupt.toml"
    corrupt.write_bytes(b"format = 1\nname = \n\xff")
    with pytest.raises(VehicleFileError, match=r"corrupt\.toml: not valid TOML"):
        load_vehicle(corrupt)
    with pytest.raises(TypeError, match="vehicle must be"):
        load_vehicle(3.5)
    assert isinstance(load_vehicle(load_vehicle()), Vehicle)
