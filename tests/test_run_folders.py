"""Commands that must not hang, fail late or share a folder: the Ray handshake, checks before the
first episode or training step, one run per output folder, the installed command's imports."""

from __future__ import annotations

import json
import os
import resource
import shutil
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from auv_gym.support.files import OUTPUTS_FILE, output_lock, remove_temporaries, replace_outputs
from benchmarks.runner import pool
from benchmarks.runner.pool import check_ray_address

ROOT = Path(__file__).resolve().parents[1]
TINY = [
    "--policies",
    "fbsm",
    "--seeds",
    "1",
    "--duration",
    "4",
    "--transient",
    "0",
    "--quiet",
    "--workers",
    "1",
]


@pytest.fixture
def closed_port() -> int:
    """A loopback port nothing listens on."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture
def silent_listener() -> Iterator[int]:
    """A loopback port that accepts connections and never says a word (not Ray)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    accepted: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                accepted.append(server.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    yield server.getsockname()[1]
    server.close()
    for conn in accepted:
        conn.close()


def one_line_exit_2(capsys, function, argv: list[str]) -> str:
    """The one stderr line of a command refusing ``argv`` with exit code 2."""
    with pytest.raises(SystemExit) as caught:
        code = function(argv)
        raise SystemExit(code)
    assert caught.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


# ------------------------------------------------------------------------------ Ray handshake
@pytest.mark.parametrize("scheme", ["", "ray://"])
def test_ray_probe_refuses_a_closed_port_at_once(scheme, closed_port):
    pytest.importorskip("ray")
    t0 = time.monotonic()
    with pytest.raises(ValueError) as error:
        check_ray_address(f"{scheme}127.0.0.1:{closed_port}", timeout_s=5.0)
    assert time.monotonic() - t0 < 2.0
    assert str(error.value).startswith(f"--address '{scheme}127.0.0.1:{closed_port}': no Ray ")
    assert "Connection refused" in str(error.value)


@pytest.mark.parametrize("scheme", ["", "ray://"])
def test_ray_probe_refuses_a_listener_that_speaks_no_ray_within_the_deadline(
    scheme, silent_listener
):
    """Was: a TCP connect, which anything listening passes (then ray.init hung)."""
    pytest.importorskip("ray")
    t0 = time.monotonic()
    with pytest.raises(ValueError, match=r"answered the handshake \(no answer within 1.5 s\)"):
        check_ray_address(f"{scheme}127.0.0.1:{silent_listener}", timeout_s=1.5)
    assert 1.4 < time.monotonic() - t0 < 4.0


@pytest.mark.parametrize("address", ["nonsense", "host:", "127.0.0.1:99999"])
def test_ray_probe_refuses_what_is_not_an_address(address):
    pytest.importorskip("ray")
    with pytest.raises(ValueError, match=r"is not HOST:PORT or ray://HOST:PORT"):
        check_ray_address(address)


def test_compare_on_an_unreachable_ray_address_fails_fast_and_names_it(
    tmp_path, capsys, silent_listener, monkeypatch
):
    """Was: `compare --backend ray --address ...` retried for ever (still at 300 s)."""
    pytest.importorskip("ray")
    from benchmarks.runner.compare import main

    monkeypatch.setattr(pool, "RAY_PROBE_TIMEOUT_S", 1.0)
    out = tmp_path / "out"
    address = f"127.0.0.1:{silent_listener}"
    t0 = time.monotonic()
    err = one_line_exit_2(
        capsys, main, [*TINY, "--backend", "ray", "--address", address, "--out", str(out)]
    )
    assert time.monotonic() - t0 < 10.0
    assert f"--address '{address}': no Ray cluster (GCS) answered the handshake" in err
    assert not out.exists()  # refused before the output folder


def _seeds_config(tmp_path: Path, **overrides) -> Path:
    section = {
        "n_envs": 4,
        "n_timesteps": 512,
        "policy": "MlpPolicy",
        "n_steps": 64,
        "batch_size": 64,
        "n_epochs": 1,
        "normalize": True,
        "env_kwargs": {"max_time": 20.0},
        **overrides,
    }
    path = tmp_path / "ppo.yml"
    path.write_text(yaml.safe_dump({"AUVPath3DSpeedLimit-v0": section}))
    return path


def _seeds_main(argv: list[str]) -> int:
    from benchmarks.training.seeds_cli import main

    return main(argv)


def test_train_seeds_refuses_a_listener_that_is_no_ray_and_writes_no_plan(
    tmp_path, capsys, silent_listener, monkeypatch
):
    """Was: the TCP connect passed, the run hung in ray.init, and its plan file then blocked the
    same command."""
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("ray")
    monkeypatch.setattr(pool, "RAY_PROBE_TIMEOUT_S", 1.0)
    out = tmp_path / "run"
    address = f"127.0.0.1:{silent_listener}"
    t0 = time.monotonic()
    err = one_line_exit_2(
        capsys,
        _seeds_main,
        [
            "--config",
            str(_seeds_config(tmp_path)),
            "--seeds",
            "2",
            "--out",
            str(out),
            "--backend",
            "ray",
            "--address",
            address,
            "--quiet",
        ],
    )
    assert time.monotonic() - t0 < 10.0
    assert f"--address '{address}': no Ray cluster (GCS) answered the handshake" in err
    assert not (out / "train_seeds.json").exists()


# --------------------------------------------------------------- checks before the first step
def test_a_huge_seed_count_is_refused_at_once_without_memory():
    """Was: `--seeds 30000000` took 2.9 GB and 15 s before anything said a word."""
    from benchmarks.training.seeds import MAX_SEEDS, parse_seeds

    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.monotonic()
    for text, count in (
        ("1000000000", 1_000_000_000),
        ("0-999999999", 1_000_000_000),
        ("1001", 1001),
    ):
        with pytest.raises(ValueError) as error:
            parse_seeds(text)
        assert str(error.value) == (
            f"--seeds {text!r} selects {count} seeds, more than "
            f"{MAX_SEEDS}: every seed is a whole training run"
        )
    assert time.monotonic() - t0 < 0.5
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50_000  # [KiB]
    assert len(parse_seeds("1000")) == 1000
    with pytest.raises(ValueError, match=r"seeds must be at most 4294967295 .*got 4294967296"):
        parse_seeds("0,4294967296")


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"learning_rate": -3e-4}, "learning_rate must be a number in (0, inf), got -0.0003"),
        (
            {"learning_rate": "lin_-1"},
            "learning_rate 'lin_-1' must be a positive number or 'lin_<x>'",
        ),
        ({"batch_size": 0}, "batch_size must be an integer >= 2, got 0"),
        ({"gamma": 1.5}, "gamma must be a number in [0, 1], got 1.5"),
        ({"gae_lambda": -0.1}, "gae_lambda must be a number in [0, 1], got -0.1"),
        ({"n_epochs": 0}, "n_epochs must be an integer >= 1, got 0"),
        ({"n_steps": 2.5}, "n_steps must be an integer >= 1, got 2.5"),
        ({"clip_range": 0}, "clip_range must be a number in (0, inf), got 0"),
        ({"ent_coef": float("nan")}, "ent_coef must be a number in [0, inf), got nan"),
        ({"max_grad_norm": 0}, "max_grad_norm must be a number in (0, inf), got 0"),
        ({"target_kl": -1}, "target_kl must be a number in (0, inf), got -1"),
        ({"normalize_advantage": "yes"}, "normalize_advantage must be true or false, got 'yes'"),
        ({"n_envs": 0}, "n_envs must be an integer >= 1, got 0"),
        ({"n_timesteps": "many"}, "n_timesteps must be a whole number >= 1, got 'many'"),
        ({"normalize": {"clip_obs": -1}}, "normalize clip_obs must be a finite number > 0, got -1"),
        ({"normalize": {"clip": 1}}, "normalize has unknown keys ['clip']"),
        ({"policy": "CnnPolicy"}, "policy must be 'MlpPolicy' (the observation is a vector)"),
        ({"policy_kwargs": {"net_arch": [64, 0]}}, "net_arch must be a list of layer sizes >= 1"),
        (
            {"policy_kwargs": {"n_layers": 2}},
            "policy_kwargs has keys ActorCriticPolicy does not take",
        ),
        ({"env_kwargs": {"max_time": -1.0}}, "env_kwargs: "),
        ({"n_steps": 1, "n_envs": 1}, "n_steps × n_envs must be at least 2"),
        # was: trained on batches of 256 after an SB3 warning
        ({"batch_size": 1000}, "batch_size 1000 exceeds the rollout n_steps × n_envs = 64 × 4"),
        ({"learning_rate": "3e-4"}, "(YAML reads 3e-4 as text: write 3.0e-4)"),
    ],
)
def test_config_values_are_refused_before_any_training(tmp_path, capsys, overrides, message):
    """Was: SB3 (or torch) refused them when the model was built, after the plan file was
    written, or trained on (γ > 1) without a word."""
    pytest.importorskip("stable_baselines3")
    out = tmp_path / "run"
    config = _seeds_config(tmp_path, **overrides)
    err = one_line_exit_2(
        capsys, _seeds_main, ["--config", str(config), "--seeds", "1", "--out", str(out), "--quiet"]
    )
    assert message in err and "AUVPath3DSpeedLimit-v0" in err
    assert not (out / "train_seeds.json").exists() and not (out / "seed_0").exists()


def test_sac_values_are_checked_too(tmp_path):
    pytest.importorskip("stable_baselines3")
    from benchmarks.training.config import read_zoo_config

    base = {"n_timesteps": 512, "policy": "MlpPolicy", "normalize": True}
    cases = (
        ({"tau": 0}, "tau must be a number in (0, 1], got 0"),
        ({"ent_coef": "autox"}, "ent_coef 'autox' must be a number >= 0"),
        ({"train_freq": [1, "hour"]}, "train_freq must be an integer"),
        ({"gradient_steps": 0}, "gradient_steps must be an integer >= 1"),
        ({"buffer_size": -5}, "buffer_size must be an integer >= 1"),
    )
    for overrides, message in cases:
        path = tmp_path / "sac.yml"
        path.write_text(yaml.safe_dump({"AUVPath3D-v0": {**base, **overrides}}))
        with pytest.raises(ValueError) as error:
            read_zoo_config(path, "AUVPath3D-v0", "sac")
        assert message in str(error.value)


def _in_a_file(tmp_path: Path) -> Path:
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    return blocker


@pytest.mark.parametrize("flag", ["--export", "--results"])
def test_train_seeds_refuses_output_folders_it_could_not_write_before_training(
    tmp_path, capsys, flag
):
    """Was: found out after every seed had trained, when the agent or results were copied."""
    pytest.importorskip("stable_baselines3")
    blocker = _in_a_file(tmp_path)
    for where, reason in (
        (blocker, "it is a file, not a folder"),
        (blocker / "agent", f"{blocker} is a file, not a folder"),
        (Path("/proc/auv-gym-test"), "/proc is not writable"),
    ):
        out = tmp_path / "run"
        err = one_line_exit_2(
            capsys,
            _seeds_main,
            [
                "--config",
                str(_seeds_config(tmp_path)),
                "--seeds",
                "1",
                "--out",
                str(out),
                "--quiet",
                flag,
                str(where),
            ],
        )
        assert f"{flag} '{where}' cannot be written as a folder: {reason}" in err
        assert not (out / "train_seeds.json").exists()


@pytest.mark.parametrize("command", ["train", "train-seeds"])
def test_an_export_that_would_delete_other_files_is_refused_before_training(
    tmp_path, capsys, command
):
    """Was: --export DIR replaced DIR whole after the training, and with it the run's own folder
    inside it (checkpoints, best/, final/), a sibling run and a user's notes."""
    pytest.importorskip("stable_baselines3")
    parent = tmp_path / "par"
    (parent / "other_run").mkdir(parents=True)
    (parent / "other_run" / "notes.txt").write_text("mine")
    out = parent / "run"
    argv = ["--config", str(_seeds_config(tmp_path)), "--out", str(out)]
    if command == "train":
        main, argv = _train_main, [*argv, "--env-id", "AUVPath3DSpeedLimit-v0", "--no-progress-bar"]
    else:
        main, argv = _seeds_main, [*argv, "--seeds", "1", "--quiet"]
    for export, message in (
        (parent, f"--export '{parent}' holds the run's own folder --out '{out}'"),
        (out, f"--export '{out}' holds the run's own folder --out '{out}'"),
        (parent / "other_run", f"--export '{parent / 'other_run'}' holds notes.txt, which are not"),
    ):
        err = one_line_exit_2(capsys, main, [*argv, "--export", str(export)])
        assert message in err
    assert (parent / "other_run" / "notes.txt").read_text() == "mine"
    assert not (out / "final").exists() and not (out / "seed_1" / "final").exists()


def test_an_agent_folder_is_replaced_and_any_other_refused(tmp_path):
    """An export replaces a folder holding an agent, its test and its ONNX export (stale once
    the agent changes); anything else there stops it before a file is written."""
    from benchmarks.training.checkpoints import EXPORTED_FILES, check_export_folder, export_agent

    source = tmp_path / "source"
    source.mkdir()
    for name in ("model.zip", "vecnormalize.npz", "metadata.json"):
        (source / name).write_text(f"new {name}")
    agent = tmp_path / "agent"
    agent.mkdir()
    for name in (*EXPORTED_FILES, "policy.onnx", "policy.json", "fins.onnx", "fins.json"):
        (agent / name).write_text("old")
    check_export_folder(agent, "--export", tmp_path / "run")
    export_agent(source, agent)
    assert sorted(p.name for p in agent.iterdir()) == [
        "metadata.json",
        "model.zip",
        "vecnormalize.npz",
    ]
    assert (agent / "model.zip").read_text() == "new model.zip"
    for name in ("README.md", "notes.json", ".hidden"):
        (agent / name).write_text("mine")
    with pytest.raises(ValueError, match=r"export '.+agent' holds \.hidden, README\.md, notes"):
        export_agent(source, agent)
    assert (agent / "README.md").read_text() == "mine"


def test_a_failed_start_does_not_block_the_corrected_command(tmp_path):
    """A plan, logs and seed folders without a checkpoint are what a start that failed before
    training leaves: a fresh start may replace them; a checkpoint or a final agent may not."""
    from benchmarks.training.seeds import holds_work

    out = tmp_path / "run"
    (out / "logs").mkdir(parents=True)
    (out / "logs" / "seed_0.log").write_text("Traceback ...\n")
    (out / "train_seeds.json").write_text("{}")
    (out / ".lock").write_text("123\n")
    (out / "seed_0" / "tb").mkdir(parents=True)
    assert not holds_work(out)
    (out / "seed_1" / "final").mkdir(parents=True)
    assert holds_work(out)
    shutil.rmtree(out / "seed_1")
    (out / "notes.txt").write_text("mine")
    assert holds_work(out)


def _train_main(argv: list[str]) -> None:
    from benchmarks.training.train_cli import main

    main(argv)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--out", "{file}"], "--out '{file}' cannot be written as a folder: it is a file, not a"),
        (["--export", "{file}/agent"], "--export '{file}/agent' cannot be written as a folder: "),
        (["--curve", "{file}/curve"], "--curve '{file}/curve.csv' cannot be written as a file: "),
        (["--curve", "{tmp}", "--eval-freq", "256"], "--curve '{tmp}.csv' cannot be written"),
        (["--curve", "{tmp}/c", "--eval-freq", "0"], "--curve plots the evaluations, and --eval-f"),
        (["--seed", "4294967296"], "--seed must be an integer in [0, 4294967295], got 4294967296"),
        (["--plot-only", "--curve", "{tmp}/c"], "--plot-only: {tmp}/run/evaluations.csv does not"),
        (["--evaluate", "{tmp}/nothing"], "{tmp}/nothing"),
    ],
)
def test_train_refuses_outputs_before_the_first_step(tmp_path, capsys, argv, message):
    """Was: a bad --curve or --export failed after the whole training."""
    pytest.importorskip("stable_baselines3")
    blocker = _in_a_file(tmp_path)
    (tmp_path / "folder.csv").mkdir()
    fill = {"file": str(blocker), "tmp": str(tmp_path)}
    argv = [a.format(**fill) for a in argv]
    if argv[:2] == ["--curve", str(tmp_path)]:
        argv[1] = str(tmp_path / "folder")  # folder.csv is a folder
        message = message.replace("{tmp}", str(tmp_path / "folder"))
    config = _seeds_config(tmp_path)
    out = [] if "--out" in argv else ["--out", str(tmp_path / "run")]
    err = one_line_exit_2(
        capsys,
        _train_main,
        [
            "--config",
            str(config),
            "--env-id",
            "AUVPath3DSpeedLimit-v0",
            *out,
            "--no-progress-bar",
            *argv,
        ],
    )
    assert message.format(**fill) in err
    assert not (tmp_path / "run").exists()


def test_video_refuses_an_unwritable_file_before_rendering(tmp_path, capsys):
    from benchmarks.reports.video import main

    blocker = _in_a_file(tmp_path)
    t0 = time.monotonic()
    err = one_line_exit_2(capsys, main, ["--out", str(blocker / "run.mp4"), "--quiet"])
    assert f"--out '{blocker}/run.mp4' cannot be written as a file: {blocker} is a file" in err
    (tmp_path / "clip.mp4").mkdir()
    err = one_line_exit_2(capsys, main, ["--out", str(tmp_path / "clip.mp4"), "--quiet"])
    assert "cannot be written as a file: it is a folder, not a file" in err
    assert time.monotonic() - t0 < 20.0


def test_a_killed_recording_leaves_no_temporary_video_behind(tmp_path, dead_pid):
    from benchmarks.reports.video import remove_stale_videos

    out = tmp_path / "run.mp4"
    dead = dead_pid
    stale = tmp_path / f".run.mp4.{dead}.tmp.mp4"
    live = tmp_path / f".run.mp4.{os.getpid()}.tmp.mp4"
    other = tmp_path / f".other.mp4.{dead}.tmp.mp4"
    for file in (stale, live, other):
        file.write_bytes(b"\0")
    assert remove_stale_videos(out) == [stale]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, other.name])


# ------------------------------------------------------------------- one output folder, one run
def test_a_second_run_on_a_locked_folder_is_refused_with_the_holders_pid(tmp_path, capsys):
    """Was: two runs on one --out deleted each other's temporary files."""
    from benchmarks.reports.paper_figures import main as paper
    from benchmarks.runner.compare import main as compare
    from benchmarks.runner.evaluate_suite import main as suite

    out = tmp_path / "out"
    expected = (
        f"--out '{out}' is in use by another run (pid {os.getpid()}); wait for it to "
        "end or choose another --out"
    )
    with output_lock(out):
        for function, argv in (
            (compare, [*TINY, "--out", str(out)]),
            (paper, ["--duration", "4", "--out", str(out)]),
            (
                suite,
                [
                    "--policies",
                    "fbsm",
                    "--no-stats",
                    "--sets",
                    "scenario:nominal",
                    "--duration",
                    "4",
                    "--out",
                    str(out),
                ],
            ),
        ):
            err = one_line_exit_2(capsys, function, argv)
            assert expected in err
        assert sorted(p.name for p in out.iterdir()) == [".lock"]  # nothing written
    with output_lock(out):  # released when the holder ends
        pass


def test_the_lock_is_released_when_its_holder_is_killed(tmp_path):
    out = tmp_path / "out"
    code = (
        f"from auv_gym.support.files import output_lock\nwith output_lock({str(out)!r}):\n"
        "    print('held', flush=True)\n    import time; time.sleep(60)\n"
    )
    holder = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=ROOT
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(OSError, match=rf"in use by another run \(pid {holder.pid}\)"):
            with output_lock(out):
                pass
    finally:
        holder.kill()
        holder.wait()
    with output_lock(out):
        assert (out / ".lock").read_text() == f"{os.getpid()}\n"


def test_temporaries_of_killed_runs_are_removed_and_others_kept(tmp_path):
    """The atomic writers' tagged temporaries go; a user's look-alikes stay. Was: any
    ".NAME.XXXXXXXX.tmp" or ".NAME.old<digits>" four levels down an output folder was deleted,
    a user's ".bashrc.old1" and ".config.old2/" with `--out ~`."""
    out = tmp_path / "out"
    stale = [
        out / ".episodes.csv.auv-gym.a1b2c3d4.tmp",
        out / "figures" / ".x.png.auv-gym.zz_9Yq0k.tmp",
        out / "episodes" / "paper" / "fbsm" / ".seed_0.npz.auv-gym.abcdefgh.tmp",
    ]
    kept = [
        out / "summary.md",
        out / "figures" / "x.png",
        out / ".hidden.tmp",
        out / "mine.abcdefgh.tmp",
        out / ".bashrc.old1",
        out / "proj" / ".notes.abcdefgh.tmp",
        out / ".config.old2" / "settings",
    ]
    for file in stale + kept:
        file.parent.mkdir(parents=True, exist_ok=True)
        file.write_text("")
    (out / ".checkpoint.auv-gym-old4242").mkdir()
    (out / ".checkpoint.auv-gym-old4242" / "model.zip").write_text("")
    with output_lock(out):
        pass
    assert all(f.exists() for f in kept)
    assert not any(f.exists() for f in stale)
    assert not (out / ".checkpoint.auv-gym-old4242").exists()
    assert remove_temporaries(out) == []


def test_a_write_killed_half_way_leaves_what_remove_temporaries_removes(tmp_path, monkeypatch):
    """The atomic writers tag their temporaries so that the next run's clean-up knows them."""
    import auv_gym.support.files as files

    def killed(source, target):
        raise KeyboardInterrupt

    monkeypatch.setattr(files.os, "replace", killed)
    monkeypatch.setattr(files.os, "unlink", lambda path: None)  # a kill skips the clean-up
    monkeypatch.setattr(files.shutil, "rmtree", lambda path, **kwargs: None)
    with pytest.raises(KeyboardInterrupt):
        files.write_text(tmp_path / "a.txt", "x")
    with pytest.raises(KeyboardInterrupt):
        files.write_folder_atomic(tmp_path / "folder", lambda tmp: (tmp / "f").write_text(""))
    monkeypatch.undo()
    left = sorted(p.name for p in tmp_path.iterdir())
    assert len(left) == 2 and all(files.TEMPORARY.fullmatch(name) for name in left), left
    assert sorted(p.name for p in remove_temporaries(tmp_path)) == left
    assert not any(tmp_path.iterdir())


def test_replace_outputs_removes_only_what_the_last_run_recorded(tmp_path):
    for name in ("a.png", "b.png", "user.png", "sub/c.png"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("")
    assert (
        replace_outputs(tmp_path, [tmp_path / "a.png", tmp_path / "b.png", tmp_path / "sub/c.png"])
        == []
    )
    assert replace_outputs(tmp_path, [tmp_path / "a.png"]) == [
        tmp_path / "b.png",
        tmp_path / "sub/c.png",
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == [OUTPUTS_FILE, "a.png", "user.png"]
    assert json.loads((tmp_path / OUTPUTS_FILE).read_text()) == {"files": ["a.png"]}


def test_compare_rerun_with_other_arguments_leaves_no_stale_figure(tmp_path):
    """Was: the figures of a run on two scenarios stayed beside the tables of a rerun on one;
    a kill during figure writing left temporary files no rerun removed."""
    from benchmarks.runner.compare import main

    out = tmp_path / "out"
    main([*TINY, "--scenarios", "nominal,paper", "--out", str(out)])
    figures = {p.name for p in (out / "figures").iterdir()}
    assert any("paper" in name for name in figures) and any("nominal" in n for n in figures)
    (out / "figures" / ".trajectory_nominal.png.auv-gym.k1ll3d00.tmp").write_text("")
    main([*TINY, "--scenarios", "nominal", "--out", str(out)])
    left = {p.name for p in (out / "figures").iterdir()}
    assert left and not any("paper" in name for name in left), left
    assert left < figures | {p.name for p in (out / "figures").iterdir()}
    main([*TINY, "--scenarios", "nominal", "--no-figures", "--out", str(out)])
    assert not (out / "figures").exists()
    assert {p.name for p in out.iterdir()} >= {"episodes.csv", "summary.md", "episodes"}


def test_paper_figures_rerun_removes_the_other_policys_files(tmp_path):
    from benchmarks.reports.paper_figures import main

    out = tmp_path / "paper"
    main(["--duration", "4", "--transient", "0", "--out", str(out)])
    assert (out / "trajectories" / "backstepping.npz").is_file()
    main(["--duration", "4", "--transient", "0", "--policies", "fbsm", "--out", str(out)])
    assert sorted(p.name for p in (out / "trajectories").iterdir()) == ["FBSM.npz"]


# ------------------------------------------------------------------------ the installed command
def test_installed_command_imports_a_policy_from_the_current_folder(tmp_path):
    """Was: `auv-gym compare --policies mymod:policy` said "No module named 'mymod'" where
    `python -m benchmarks compare` found ./mymod.py."""
    script = Path(sys.executable).with_name("auv-gym")
    if not script.is_file():
        pytest.skip("auv-gym is not installed in this environment")
    shutil.copy(ROOT / "tests" / "user_policy.py", tmp_path / "mymod.py")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [
            str(script),
            "compare",
            "--policies",
            "mymod:policy",
            "--scenarios",
            "nominal",
            *TINY[2:],
            "--no-figures",
            "--out",
            "out",
        ],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    rows = (tmp_path / "out" / "episodes.csv").read_text().splitlines()
    assert len(rows) == 2 and rows[1].startswith("nominal,mymod:policy,0,")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["env", "--steps", "0"], "--steps and --reference-steps must be >= 1"),
        (
            ["vector", "--quick", "--json", "{file}/x.json"],
            "--json '{file}/x.json' cannot be written as a file: {file} is a file, not a folder",
        ),
        (
            ["training", "--quick", "--json", "{file}/x.json"],
            "--json '{file}/x.json' cannot be written as a file: {file} is a file, not a folder",
        ),
    ],
)
def test_speed_benchmarks_refuse_options_before_timing(tmp_path, capsys, argv, message):
    """Was: `speed env --steps 0` ended in an IndexError traceback, and a bad --json was found
    after the whole benchmark had run."""
    from benchmarks.cli import main

    blocker = _in_a_file(tmp_path)
    t0 = time.monotonic()
    assert main(["speed", *(a.format(file=blocker) for a in argv)]) == 2
    assert message.format(file=blocker) in capsys.readouterr().err
    assert time.monotonic() - t0 < 10.0


def _fake_seed(out: Path, seed: int) -> dict:
    """The files `_write_results` reads for one finished seed (contents are placeholders)."""
    from controllers.agent import METADATA_FILE, MODEL_FILE, STATS_FILE

    agent = out / f"seed_{seed}" / "best"
    agent.mkdir(parents=True)
    for name in (MODEL_FILE, STATS_FILE, METADATA_FILE):
        (agent / name).write_text(f"{name} of seed {seed}")
    (agent / "held_out_evaluation.json").write_text(json.dumps({"seed": seed}))
    (out / f"seed_{seed}" / "evaluations.csv").write_text("num_timesteps\n0\n")
    return {"seed": seed, "agent": str(agent)}


def test_results_of_a_run_with_other_seeds_are_replaced_not_mixed(tmp_path):
    """Was: a rerun of train_seeds --results with seeds 0-1 after seeds 0-2 left
    agent_seed_2/, which the suite (NAME=DIR) then evaluated as a seed of the new run."""
    from benchmarks.training.seeds import _write_results

    out, results = tmp_path / "run", tmp_path / "results"
    entries = [_fake_seed(out, seed) for seed in range(3)]
    _write_results(results, out, entries, {"seeds": [0, 1, 2]})
    assert (results / "agent_seed_2" / "model.zip").is_file()
    (results / "my_notes.md").write_text("kept")
    _write_results(results, out, entries[:2], {"seeds": [0, 1]})
    assert sorted(p.name for p in results.iterdir()) == [
        OUTPUTS_FILE,
        "agent_seed_0",
        "agent_seed_1",
        "my_notes.md",
        "seed_0_learning_curve.csv",
        "seed_0_test_evaluation.json",
        "seed_1_learning_curve.csv",
        "seed_1_test_evaluation.json",
        "summary.json",
    ]


def test_train_refuses_an_unknown_vec_env_and_an_unregistered_env_id(tmp_path, capsys):
    """Was: both raised inside the training, after the run folder was made."""
    pytest.importorskip("stable_baselines3")
    config = _seeds_config(tmp_path)
    base = ["--config", str(config), "--out", str(tmp_path / "run"), "--no-progress-bar"]
    err = one_line_exit_2(
        capsys, _train_main, [*base, "--env-id", "AUVPath3DSpeedLimit-v0", "--vec-env", "fast"]
    )
    assert "argument --vec-env: invalid choice: 'fast'" in err
    config.write_text(
        yaml.safe_dump({"Nope-v0": yaml.safe_load(config.read_text())["AUVPath3DSpeedLimit-v0"]})
    )
    err = one_line_exit_2(capsys, _train_main, [*base, "--env-id", "Nope-v0"])
    assert f"{config}: Nope-v0: Environment `Nope` doesn't exist" in err
    assert not (tmp_path / "run").exists()


def test_train_seeds_refuses_an_address_without_ray_and_trains_nothing(tmp_path, capsys):
    """Was: `train-seeds --address` without `--backend ray` trained locally in silence."""
    pytest.importorskip("stable_baselines3")
    out = tmp_path / "run"
    argv = ["--config", str(_seeds_config(tmp_path)), "--seeds", "1", "--out", str(out)]
    err = one_line_exit_2(capsys, _seeds_main, [*argv, "--address", "127.0.0.1:6379"])
    assert "--address needs --backend ray" in err
    assert not out.exists()
