"""The report table of the suite statistics (`benchmarks.analysis.report_spec`): the shipped
file holds the shipped results' experiment, a custom one changes what is compared, and bad
tables are refused with one line naming the key."""

from __future__ import annotations

import pytest

from benchmarks.analysis.report_spec import DEFAULT_REPORT, ReportSpec


def test_the_shipped_table_is_the_shipped_experiment():
    spec = ReportSpec.read()
    assert spec == ReportSpec(
        reference="fbsm",
        extra_references=("fbsm_colos",),
        max_ratio=1.5,
        target_references=("fbsm", "fbsm_colos"),
        smoothness_reference="fbsm",
        worse_ratio=0.10,
        pairs=(
            ("ppo_residual", "fbsm_colos"),
            ("ppo_residual_v2", "fbsm_colos"),
            ("fbsm_colos_lowpass", "fbsm_colos"),
            ("ppo_residual", "fbsm_colos_lowpass"),
        ),
        tradeoff_scopes=("scenario:paper", "test_distribution", "aggregate"),
    )
    assert DEFAULT_REPORT.name == "report.toml"
    # --reference replaces the reference only; chattering ratios keep theirs
    other = spec.with_reference("backstepping")
    assert (other.reference, other.smoothness_reference) == ("backstepping", "fbsm")
    assert other.target_references == ()  # the target then refers to --reference alone
    assert spec.with_reference(None) is spec


def test_a_minimal_table_takes_defaults_and_its_reference_for_smoothness(tmp_path):
    path = tmp_path / "r.toml"
    path.write_text('reference = "pid_los"\n[smoothness]\npairs = [["a", "b"]]\n')
    spec = ReportSpec.read(path)
    assert spec.smoothness_reference == "pid_los" and spec.pairs == (("a", "b"),)
    assert (spec.max_ratio, spec.worse_ratio, spec.extra_references) == (2.0, 0.1, ())


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('reference = "fbsm"\nrefrence = 1\n', r"unknown keys \['refrence'\]"),
        ("[target]\nmax_ratio = 2\n", "reference must be a policy name, got None"),
        (
            'reference = "fbsm"\n[target]\nmax_ratio = -1\n',
            "target.max_ratio must be a positive number, got -1",
        ),
        (
            'reference = "fbsm"\n[smoothness]\npairs = [["a"]]\n',
            r"smoothness.pairs must be a list of \[policy, base\]",
        ),
        ('reference = "fbsm"\n[smoothness]\nparis = []\n', r"\[smoothness\] unknown keys"),
        (
            'reference = "fbsm"\n[target]\nreferences = "fbsm"\n',
            "target.references must be a list of names",
        ),
        ("reference = ", "report table .*bad.toml: not valid TOML"),
    ],
)
def test_bad_tables_are_one_line_naming_the_file_and_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message) as error:
        ReportSpec.read(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)
