"""The PID tuner's grid and base (`benchmarks.analysis.tune_pid`): any PID preset, any of its
gains, bad grids refused by name before anything flies."""

from __future__ import annotations

import math

import pytest

from benchmarks.analysis.tune_pid import (
    GRID,
    candidate_policies,
    check_base,
    main,
    parse_grid,
    tune,
)


def test_a_grid_names_pid_gains_with_finite_values() -> None:
    assert parse_grid("pitch_wn=1.5,2; k_z=0.1") == {"pitch_wn": (1.5, 2.0), "k_z": (0.1,)}
    for text, message in [
        ("pitch_wn", "is not NAME=V1,V2"),
        ("pitch_wn=", "is not NAME=V1,V2"),
        ("=1,2", "is not NAME=V1,V2"),
        ("h=1", "'h' is not a PID gain"),
        ("speed_over_ground=0,1", "'speed_over_ground' is not a PID gain"),
        ("pitch_wn=1;pitch_wn=2", "more than once"),
        ("pitch_wn=1,x", "--grid pitch_wn"),
        ("pitch_wn=1,inf", "must be finite"),
        ("pitch_wn=1,,2", "empty name"),
    ]:
        with pytest.raises(ValueError, match=message):
            parse_grid(text)


def test_the_base_is_a_pid_preset(capsys) -> None:
    check_base("pid_as_built_climb")
    with pytest.raises(ValueError, match="'fbsm_colos' is not a PID preset"):
        check_base("fbsm_colos")
    with pytest.raises(SystemExit):  # before any episode flies
        main(["--base", "nope"])
    with pytest.raises(SystemExit):
        main(["--grid", "pitch_wn=nan"])
    with pytest.raises(SystemExit):  # a gain the controller refuses, before any episode flies
        main(["--scenarios", "as_built_helix", "--grid", "pitch_wn=0.5,2"])
    for seeds, message in (
        ("-100", "--seeds must be integers >= 0, got '-100'"),  # was a traceback
        ("abc", "--seeds must be comma-separated integers, got 'abc'"),  # was a bare int() error
    ):
        with pytest.raises(SystemExit):
            main(["--seeds", seeds])
        assert message in capsys.readouterr().err
    with pytest.raises(ValueError, match=r"PIDGains\.pitch_wn = 0\.5 rad/s"):
        candidate_policies(["as_built_helix"], 60.0, {"pitch_wn": (0.5,)}, "pid_as_built_climb")


def test_the_climb_speed_pid_tuned_on_its_pitch_loop() -> None:
    """Two pitch loops of the climb-speed PID on one validation seed of the as-built helix (60 s):
    each flown, both finish, ranked by their mean RMS distance; the candidates differ."""
    rows = tune(
        ["as_built_helix"],
        [100],
        60.0,
        grid={"pitch_wn": (2.0, 3.0)},
        progress=False,
        base="pid_as_built_climb",
    )
    assert sorted(r["gains"]["pitch_wn"] for r in rows) == [2.0, 3.0]
    assert [r["failed"] for r in rows] == [0, 0]
    distances = [r["rms"]["as_built_helix"] for r in rows]
    assert distances == sorted(distances)
    assert all(0.01 < d < 5.0 for d in distances)  # m, converging from the start
    assert not math.isclose(distances[0], distances[1], rel_tol=1e-6)
    assert set(GRID) == {"design_speed", "yaw_wn", "k_y", "k_z"}  # the default grid unchanged


def test_a_users_scenario_file_is_tuned_on(tmp_path, capsys) -> None:
    """--scenario-file: the tuner flies the scenarios of a user's file, their vehicle file beside
    it (docs/vehicles.md §4); a missing file or an unknown name is one line before any flight."""
    import shutil

    from auv_gym.vehicle.record import VEHICLE_DIRECTORY

    shutil.copy(VEHICLE_DIRECTORY / "remus100.toml", tmp_path / "mine.toml")
    scenarios = tmp_path / "mine_scenarios.toml"
    scenarios.write_text('[mine_helix]\nvehicle = "mine.toml"\nenv = { disturbance = "none" }\n')
    argv = ["--scenario-file", str(scenarios), "--scenarios", "mine_helix", "--seeds", "100"]
    rows = main([*argv, "--duration", "20", "--grid", "k_y=0.1,0.2"])
    assert [r["failed"] for r in rows] == [0, 0]
    assert all(0.0 < r["rms"]["mine_helix"] < 20.0 for r in rows)  # m, from the paper's start
    assert "best (controllers.make('pid_as_built'" in capsys.readouterr().out
    for bad, message in [
        ([*argv[:1], str(tmp_path / "absent.toml"), *argv[2:]], "absent.toml"),
        ([*argv[:3], "helix_9", *argv[4:]], "--scenarios: unknown ['helix_9'] in mine_scenarios"),
    ]:
        with pytest.raises(SystemExit):
            main(bad)
        assert message in capsys.readouterr().err
