"""How evaluations rank to keep a run's best agent (`benchmarks.training.selection_rule`).

The default rule is the committed one (failures first, then the pooled mean); a ``selection``
section lets the first k failures not count first and puts each actuator on its own scale
(geometric mean). On a recorded learning curve (the fin-share pilot's light seed 0, base phase)
the default keeps the agent of 250k steps and the ranked rule the one of 3M. Bad sections are
refused in one line naming the entry; a tiny run records the rule and scores by it."""

from __future__ import annotations

import json
import math

import pytest
import yaml

from benchmarks.training.evaluation import score
from benchmarks.training.selection_rule import (
    DEFAULT_RULE,
    SelectionRule,
    parse_selection,
    rule_of,
)

# Base phase of the light fin-share pilot's seed 0 (its evaluations.csv): steps, then
# (mean rms [m], terminated) on the paper's actuator and on the fins, 16 episodes each.
PILOT_SEED_0_BASE = [
    (0, (0.180186, 0), (0.5754, 1)),
    (250016, (0.096529, 0), (0.366345, 0)),
    (500000, (0.0836176, 0), (0.392702, 0)),
    (750016, (0.0818936, 0), (0.377684, 1)),
    (1500000, (0.0758503, 0), (0.321326, 1)),
    (2500000, (0.0645827, 0), (0.28688, 1)),
    (3000000, (0.0624383, 0), (0.271709, 1)),
]


def summary_of(paper: tuple[float, int], fins: tuple[float, int]) -> dict:
    """A validation summary of 16 + 16 episodes with these per-actuator means and failures."""
    return {
        "rms_distance_mean": (paper[0] + fins[0]) / 2,
        "n_terminated": paper[1] + fins[1],
        "per_variant": {
            "paper": {"rms_distance_mean": paper[0], "n_terminated": paper[1]},
            "fins": {"rms_distance_mean": fins[0], "n_terminated": fins[1]},
        },
    }


def best_step(rule: SelectionRule) -> int:
    """The step a run keeps: the first evaluation of lowest score (a later one must improve)."""
    best = None
    for steps, paper, fins in PILOT_SEED_0_BASE:
        current = rule.score(summary_of(paper, fins))
        if best is None or current < best[0]:
            best = (current, steps)
    return best[1]


def test_the_default_rule_is_the_committed_score_failures_first_then_the_pooled_mean():
    for _, paper, fins in PILOT_SEED_0_BASE:
        summary = summary_of(paper, fins)
        assert DEFAULT_RULE.score(summary) == score(summary)
        assert score(summary) == (paper[1] + fins[1], (paper[0] + fins[0]) / 2)
    assert best_step(DEFAULT_RULE) == 250016


def test_the_ranked_rule_keeps_the_accurate_agent_that_failed_one_fin_episode():
    ranked = SelectionRule(failures_allowed=1, across_variants="geometric")
    assert best_step(ranked) == 3000000
    failed, value = ranked.score(summary_of((0.0624383, 0), (0.271709, 1)))
    assert failed == 0 and value == pytest.approx(math.sqrt(0.0624383 * 0.271709), rel=1e-12)
    # beyond the allowance failures count first again: two fail, one counts
    assert ranked.score(summary_of((0.05, 1), (0.2, 1)))[0] == 1


def test_the_geometric_mean_weighs_relative_gains_on_each_actuator_alike():
    geometric = SelectionRule(across_variants="geometric")
    pooled = SelectionRule()
    base = summary_of((0.06, 0), (0.30, 0))
    paper_gain = summary_of((0.054, 0), (0.30, 0))  # 10 % better on the paper's actuator
    fins_gain = summary_of((0.06, 0), (0.27, 0))  # 10 % better on the fins
    assert geometric.score(paper_gain)[1] == pytest.approx(geometric.score(fins_gain)[1])
    assert geometric.score(paper_gain) < geometric.score(base)
    # pooled, the fins' gain is worth five times the paper's
    assert base["rms_distance_mean"] - pooled.score(paper_gain)[1] == pytest.approx(0.003)
    assert base["rms_distance_mean"] - pooled.score(fins_gain)[1] == pytest.approx(0.015)


def test_a_validation_without_variants_scores_as_pooled_and_nan_scores_last():
    ranked = SelectionRule(failures_allowed=1, across_variants="geometric")
    plain = {"rms_distance_mean": 0.07, "n_terminated": 0}
    assert ranked.score(plain) == (0, 0.07)
    broken = summary_of((math.nan, 0), (0.3, 0))
    assert ranked.score(broken) == (0, math.inf)
    chattering = {**plain, "chattering_mean": 2.0}
    assert ranked.score(chattering, 0.01) == (0, pytest.approx(0.09))


@pytest.mark.parametrize(
    ("section", "message"),
    [
        ([1], "selection must be a mapping"),
        ({"failures": 1}, "selection: unknown keys ['failures']"),
        ({"failures_allowed": True}, "failures_allowed must be a whole number of episodes"),
        ({"failures_allowed": 1.5}, "failures_allowed must be a whole number of episodes"),
        ({"failures_allowed": -1}, "failures_allowed must be 0-1000 episodes, got -1"),
        ({"across_variants": "mean"}, "across_variants: unknown value 'mean'"),
    ],
)
def test_a_bad_selection_section_is_refused_naming_the_entry(section, message):
    with pytest.raises(ValueError, match=r"^here: ") as error:
        parse_selection(section, "here")
    assert message in str(error.value) and "\n" not in str(error.value)


def test_the_rule_round_trips_through_the_metadata_it_is_recorded_in():
    ranked = parse_selection({"failures_allowed": 2, "across_variants": "geometric"}, "x")
    assert rule_of({"config": {"selection": ranked.to_dict()}}) == ranked
    assert rule_of({"config": {"n_envs": 4}}) == DEFAULT_RULE and rule_of({}) == DEFAULT_RULE
    assert ranked.describe() == (
        "terminated episodes beyond 2, then geometric mean over the variants of their mean "
        "rms distance"
    )


def test_a_hyper_parameter_file_reads_its_selection_and_refuses_a_bad_one(tmp_path):
    from benchmarks.training.config import read_zoo_config

    section = {
        "n_envs": 2,
        "n_timesteps": 64,
        "policy": "MlpPolicy",
        "normalize": True,
        "n_steps": 32,
        "batch_size": 32,
        "selection": {"failures_allowed": 1, "across_variants": "geometric"},
    }
    path = tmp_path / "ranked.yml"
    path.write_text(yaml.safe_dump({"AUVPath3D-v0": section}))
    assert read_zoo_config(path, "AUVPath3D-v0").selection == SelectionRule(1, "geometric")
    path.write_text(yaml.safe_dump({"AUVPath3D-v0": {**section, "selection": {"k": 1}}}))
    with pytest.raises(ValueError, match="unknown keys \\['k'\\]") as error:
        read_zoo_config(path, "AUVPath3D-v0")
    assert str(path) in str(error.value)


@pytest.mark.rl
def test_a_tiny_run_on_two_actuators_keeps_its_best_agent_by_the_files_rule(tmp_path):
    """A tiny PPO run validated on the paper's actuator and the fins: the recorded best score is
    the rule's score of the recorded best summary, every evaluation ranks by it, and the
    seeds summary names the rule."""
    pytest.importorskip("stable_baselines3")
    from benchmarks.training.learning_curve import read_rows
    from benchmarks.training.seeds_cli import main

    section = {
        "n_envs": 2,
        "n_timesteps": 384,
        "policy": "MlpPolicy",
        "normalize": True,
        "n_steps": 64,
        "batch_size": 64,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=[16, 16])",
        "env_kwargs": {"observation": "preview_integral", "max_time": 20.0},
        "selection": {"failures_allowed": 1, "across_variants": "geometric"},
    }
    config = tmp_path / "ranked.yml"
    config.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    out = tmp_path / "run"
    argv = ["--config", str(config), "--env-id", "AUVPath3DPreview-v0", "--seeds", "0-0"]
    argv += ["--workers", "1", "--task-set", "validation_actuators_start_light"]
    argv += ["--eval-episodes", "1", "--eval-freq", "128", "--eval-duration", "110", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    meta = json.loads((out / "seed_0" / "final" / "metadata.json").read_text())
    rule = rule_of(meta)
    assert rule == SelectionRule(1, "geometric")
    best = meta["best"]
    assert set(best["summary"]["per_variant"]) == {"paper", "fins"}
    assert list(rule.score(best["summary"])) == pytest.approx(best["score"])
    rows = read_rows(out / "seed_0" / "evaluations.csv")
    assert [int(r["num_timesteps"]) for r in rows] == [0, 128, 256, 384]
    scores = [
        rule.score(
            summary_of(
                (float(r["rms_distance_mean_paper"]), int(r["n_terminated_paper"])),
                (float(r["rms_distance_mean_fins"]), int(r["n_terminated_fins"])),
            )
        )
        for r in rows
    ]
    kept = min(range(len(rows)), key=lambda i: scores[i])  # first of the lowest
    assert best["num_timesteps"] == int(rows[kept]["num_timesteps"])
    summary = json.loads((out / "summary.json").read_text())
    assert "terminated episodes beyond 1, then geometric mean" in summary["selection"]
