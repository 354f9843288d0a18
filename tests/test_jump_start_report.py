"""benchmarks.analysis.jump_start: a jump-started seed's curve runs on across its phases, and the
first evaluation beating a reference counts only one with no failed episode."""

from __future__ import annotations

from pathlib import Path

from benchmarks.analysis.jump_start import seed_curves, summarise, write_markdown

HEADER = (
    "num_timesteps,wall_time_s,rms_distance_mean,rms_distance_std,rms_distance_max,n_terminated\n"
)


def _phase(run: Path, folder: str, seed: int, rows: list[str]) -> None:
    path = run / folder / f"seed_{seed}"
    path.mkdir(parents=True)
    (path / "evaluations.csv").write_text(HEADER + "".join(r + "\n" for r in rows))


def test_curves_accumulate_across_phases_and_failures_do_not_count(tmp_path: Path) -> None:
    run = tmp_path / "jump"
    _phase(run, "phase_1_jump_start", 0, ["32768,10.0,0.30,0,0,2", "65536,20.0,0.25,0,0,0"])
    _phase(
        run,
        "phase_2_base",
        0,
        ["0,1.0,0.25,0,0,0", "250016,61.0,0.09,0,0,1", "500000,121.0,0.08,0,0,0"],
    )
    _phase(run, "phase_10_late", 0, ["0,1.0,0.07,0,0,0"])  # phases sort by number, not text
    curve = seed_curves(run)[0]
    assert [e["phase"] for e in curve] == ["jump_start"] * 2 + ["base"] * 3 + ["late"]
    assert [e["env_steps"] for e in curve] == [32768, 65536, 65536, 315552, 565536, 565536]
    assert [e["wall_time_s"] for e in curve] == [10.0, 20.0, 21.0, 81.0, 141.0, 142.0]
    references = {
        "fbsm": {"rms_distance": 0.28, "failed": 0},
        "fbsm_colos": {"rms_distance": 0.094, "failed": 0},
    }
    summary = summarise({"jump start": {0: curve}}, references)
    beats = summary["jump start"]["0"]["beats"]
    assert beats["fbsm"]["env_steps"] == 65536  # 0.30 with failures does not count
    assert beats["fbsm_colos"]["env_steps"] == 565536  # 0.09 at 315552 had a failed episode
    write_markdown(summary, references, ("validation_paper_start", 16, 200.0), tmp_path / "s.md")
    text = (tmp_path / "s.md").read_text()
    assert (
        "| jump start | 0 | 0.07 M steps, 0.3 min (jump_start) | 0.57 M steps, 2.4 min (base)"
        in text
    )
