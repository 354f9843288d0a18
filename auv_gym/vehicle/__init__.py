"""The vehicle: its parameter record, equations of motion, actuators and sensors.

- `params`: `AUVParams` (REMUS 100 by default, `remus100`) and its packed form for the kernels;
- `dynamics`: the equations of motion and the virtual point's ṡ (the simulator state `STATE`);
- `actuators`: `ActuatorParams`, the fin and propeller models and the actuator state;
- `sensors`: `SensorConfig`, the error model of the navigation suite (DVL, AHRS, depth, fixes);
- `record`: `Vehicle`, all of the above for one vehicle, read from its TOML file (`load_vehicle`,
  the shipped files in `data/`).

Imports `auv_gym.support` and `auv_gym.paths` (the state's s is the virtual point's).
"""

from __future__ import annotations

from auv_gym.vehicle.actuators import (
    ACTUATOR_COMMANDS,
    ActuatorParams,
    actuator_params_from_spec,
)
from auv_gym.vehicle.dynamics import STATE, STATE_DIM, STATE_NAMES
from auv_gym.vehicle.params import AUVParams, params_from_spec, remus100
from auv_gym.vehicle.record import (
    Vehicle,
    VehicleFileError,
    load_vehicle,
    shipped_vehicles,
)
from auv_gym.vehicle.sensors import SENSOR_PRESETS, SensorConfig

__all__ = [
    "ACTUATOR_COMMANDS",
    "SENSOR_PRESETS",
    "STATE",
    "STATE_DIM",
    "STATE_NAMES",
    "AUVParams",
    "ActuatorParams",
    "SensorConfig",
    "Vehicle",
    "VehicleFileError",
    "actuator_params_from_spec",
    "load_vehicle",
    "params_from_spec",
    "remus100",
    "shipped_vehicles",
]
