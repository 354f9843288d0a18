"""`benchmarks.analysis.steady_offset`: FBSM holds the calm helix without a steady offset, at u_D,
and is infinitely stiff against a constant pitch or thrust bias (its adaptation absorbs them);
bad input is named."""

from __future__ import annotations

import json

import pytest

from benchmarks.analysis.steady_offset import main


def test_fbsm_has_no_steady_offset_and_absorbs_a_pitch_and_a_thrust_bias(tmp_path, capsys):
    out = tmp_path / "offset.json"
    rows = main(
        [
            "--policies",
            "fbsm",
            "--seeds",
            "1",
            "--bias",
            "0.1",
            "--surge-bias",
            "-0.1",
            "--json",
            str(out),
        ]
    )
    fbsm = rows["fbsm"]
    assert max(abs(v) for v in fbsm["calm_mean"]) < 0.03  # [m]
    assert abs(fbsm["stiffness_z"]) < 0.02  # [m per unit command]
    assert abs(fbsm["calm_surge"] - 1.0) < 1e-3  # [m/s] u_D of the paper
    # a tenth of the thrust range moves its speed and along-track error by less than 2 mm/s, 2 mm
    assert abs(fbsm["surge_u"]) < 0.02 and abs(fbsm["surge_x"]) < 0.02
    assert fbsm["noisy_failed"] == 0 and 0.03 < fbsm["rms_distance"] < 0.1
    assert 20.0 < fbsm["max_pitch_deg"] < 60.0
    assert json.loads(out.read_text())["rows"]["fbsm"]["calm_mean"] == fbsm["calm_mean"]
    assert "| fbsm |" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seeds", "0"], "--seeds must be >= 1"),
        (["--bias", "2"], "--bias must be finite with 0 < |b| <= 1"),
        (["--surge-bias", "nan"], "--surge-bias must be finite with 0 < |b| <= 1"),
        (["--policies", "nope"], "nope"),
        (["--policies", "a=/no/such/agent"], "does not exist"),
    ],
)
def test_bad_input_is_one_line(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
