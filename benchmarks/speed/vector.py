"""Vector-env speed: vehicle-steps/s and real-time factor, peak memory, SB3 PPO data collection.

1. `AUVPath3DVectorEnv` with default physics (RK4 at 0.01 s, 5 physics steps per 0.05 s control
   step) and the paper's white noise, N ∈ {1, 64, 1024, 4096, 16384} vehicles, random actions and
   a short `max_time` so that NEXT_STEP autoresets happen throughout the timed loop.
   Physics vehicle-steps/s = control vehicle-steps/s × 5; aggregate real-time factor =
   simulated seconds of all vehicles per wall-clock second. Each size runs once per actuator
   model of ``--actuators``, side by side ("realistic": propeller and fin dynamics,
   docs/model.md §2.6). Beside them, side by side: waves, the sensor model, the whole
   vehicle as built (`AS_BUILT`), the as-built vehicle with its guidance computer
   (docs/model.md §14.9) and the 6-DOF plant (docs/model.md §15).
2. Peak resident memory of N = 65,536 vehicles (reset, then stepped), in a fresh subprocess:
   growth of `ru_maxrss` over the same process after imports and compilation.
3. SB3 PPO rollout collection (`collect_rollouts`, MlpPolicy, torch on one thread) through the
   `auv_gym.envs.sb3` adapter, against SB3's DummyVecEnv over single envs, each in a fresh process.

    python -m benchmarks.speed.vector             # full run (about 2 minutes)
    python -m benchmarks.speed.vector --quick     # smoke test

Wall-clock numbers depend on the load of the machine; the load average is printed with them.
"""

from __future__ import annotations

import json
import math
import os
import platform
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from auv_gym.support.files import write_json
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.options import option

SIZES = (1, 64, 1024, 4096, 16384)
MEMORY_N = 65_536


def _actions(n: int, count: int, seed: int) -> np.ndarray:
    """A bank of random action batches (count, n, 3), moderate like tests/test_env.py's."""
    a = np.random.default_rng(seed).uniform(-1.0, 1.0, size=(count, n, 3)).astype(np.float32)
    a[..., 0] = 0.2 + 0.3 * np.abs(a[..., 0])
    a[..., 1:] *= 0.3
    return a


def measure_vector(
    n: int,
    seconds: float,
    max_time: float,
    threads: int | None = None,
    seed: int = 0,
    actuator: str = "paper",
    env_kwargs: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Time `AUVPath3DVectorEnv.step` for `seconds` of wall clock, compilation excluded.

    The loop runs at least 1.25 episodes so that every vehicle goes through a NEXT_STEP
    autoreset; the time spent inside the compiled kernel is recorded separately (the rest is
    the env's Python glue: validation, truncation, infos, resets).
    """
    from auv_gym.envs.vector_env import AUVPath3DVectorEnv

    # Defaults otherwise: helix, ±35 white noise, RK4 at 0.01 s, control every 0.05 s.
    kwargs = {"actuator": actuator, **(env_kwargs or {})}  # env_kwargs may name the actuator
    env = AUVPath3DVectorEnv(n, max_time=max_time, threads=threads, **kwargs)
    bank = _actions(n, 16, seed)
    env.reset(seed=seed)
    env.step(bank[0])  # compile / load the kernel outside the timed loop
    kernel_step, kernel_time = env.sim.step, [0.0]

    def timed_kernel(actions: np.ndarray) -> None:
        t0 = time.perf_counter()
        kernel_step(actions)
        kernel_time[0] += time.perf_counter() - t0

    env.sim.step = timed_kernel
    min_steps = math.ceil(1.25 * env.config.max_steps)
    steps, resets, ended = 0, 0, np.zeros(n, dtype=bool)
    start = time.perf_counter()
    while True:
        for a in bank:
            _, _, terminated, truncated, _ = env.step(a)
            resets += int(ended.sum())  # NEXT_STEP: rows that ended last step reset now
            ended = terminated | truncated
        steps += len(bank)
        wall = time.perf_counter() - start
        if wall >= seconds and steps >= min_steps:
            break
    cfg = env.config
    vehicle_steps = steps * n
    return {
        "n": n,
        "actuator": env.config.actuator,
        "threads": env.threads,
        "batch_steps": steps,
        "vehicle_steps_per_s": vehicle_steps / wall,
        "physics_steps_per_s": vehicle_steps * cfg.substeps / wall,
        "real_time_factor": vehicle_steps * cfg.control_dt / wall,
        "ms_per_batch_step": 1e3 * wall / steps,
        "glue_fraction": 1.0 - kernel_time[0] / wall,
        "autoresets": resets,
        "sensors": env.config.sensors.preset,
    }


def _side_by_side(
    args: Options,
    sizes: list[int],
    variant: dict[str, Any],
    labels: tuple[str, str],
    common: dict[str, Any] | None = None,
) -> list[dict[str, Any]]:
    """Physics rate without and with ``variant`` (env keyword arguments; ``common`` on both
    sides), measured back to back per (threads, N) so that their ratio is taken under one machine
    load; printed as a table and returned as rows {n, threads, ratio, <labels[0]>, <labels[1]>}."""
    common = dict(common or {})
    print(f"{'N':>7} {'threads':>7} {labels[0]:>14} {labels[1]:>14} {'ratio':>7}")
    rows = []
    for threads, n in ((t, n) for t in args.threads for n in sizes):
        base = measure_vector(n, args.seconds, args.max_time, threads, env_kwargs=common)
        other = measure_vector(
            n, args.seconds, args.max_time, threads, env_kwargs={**common, **variant}
        )
        ratio = other["physics_steps_per_s"] / base["physics_steps_per_s"]
        rows.append(
            {"n": n, "threads": base["threads"], "ratio": ratio, labels[0]: base, labels[1]: other}
        )
        print(
            f"{n:>7} {base['threads']:>7} {base['physics_steps_per_s']:>14,.0f} "
            f"{other['physics_steps_per_s']:>14,.0f} {ratio:>7.1%}"
        )
    return rows


def _sensor_rows(args: Options) -> list[dict[str, Any]]:
    """Physics rate with "ideal" and "typical" sensors, side by side (`_side_by_side`)."""
    print(
        "\nSensor model: physics steps/s with the exact state ('ideal') and the navigation "
        "estimate ('typical'), side by side"
    )
    return _side_by_side(args, args.sensor_sizes, {"sensors": "typical"}, ("ideal", "typical"))


def measure_memory(n: int, steps: int = 20) -> dict[str, float]:
    """Peak RSS of n vehicles: run in this process (call it in a fresh one, see `main`)."""
    from auv_gym.envs.vector_env import AUVPath3DVectorEnv

    warm = AUVPath3DVectorEnv(2)
    warm.reset(seed=0)
    warm.step(np.zeros((2, 3)))  # imports and compiled kernels are part of the baseline
    del warm
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB
    start = time.perf_counter()
    env = AUVPath3DVectorEnv(n, max_time=5.0)
    env.reset(seed=0)
    reset_s = time.perf_counter() - start
    bank = _actions(n, 4, 1)
    start = time.perf_counter()
    for k in range(steps):
        env.step(bank[k % len(bank)])
    step_s = (time.perf_counter() - start) / steps
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return {
        "n": n,
        "baseline_bytes": before,
        "peak_bytes": peak,
        "growth_bytes": peak - before,
        "reset_s": reset_s,
        "step_s": step_s,
    }


def _fresh_process(call: str) -> Any:
    """Evaluate ``call`` (an expression over this module) in a new interpreter; JSON result.

    Memory needs its own process for `ru_maxrss`; PPO collection one where numba's OpenMP
    pool was never started by the threaded throughput runs (its spinning slows torch).
    """
    code = f"import json; import benchmarks.speed.vector as m; print(json.dumps(m.{call}))"
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=root
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure_ppo_collection(
    n_envs: int, n_steps: int, repeats: int, backend: str, seed: int = 0
) -> dict[str, float]:
    """Timesteps/s of PPO's `collect_rollouts` (policy forward + env step + buffer)."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    from auv_gym import AUVPath3DEnv
    from auv_gym.envs.sb3 import make_sb3_vec_env

    torch.set_num_threads(1)  # docs/design.md §4: one thread is as fast for these small networks
    kwargs = {"max_time": 30.0, "randomize_start": True}
    if backend == "adapter":
        env = make_sb3_vec_env(n_envs, seed=seed, **kwargs)
    else:
        env = DummyVecEnv([lambda: AUVPath3DEnv(**kwargs) for _ in range(n_envs)])
        env.seed(seed)
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=n_steps,
        batch_size=n_envs * n_steps,
        seed=seed,
        device="cpu",
        verbose=0,
    )
    _, callback = model._setup_learn(n_envs * n_steps * (repeats + 1), None)
    callback.on_training_start(locals(), globals())
    model.collect_rollouts(env, callback, model.rollout_buffer, n_rollout_steps=n_steps)  # warm-up
    start = time.perf_counter()
    for _ in range(repeats):
        model.collect_rollouts(env, callback, model.rollout_buffer, n_rollout_steps=n_steps)
    wall = time.perf_counter() - start
    return {
        "backend": backend,
        "n_envs": n_envs,
        "timesteps_per_s": repeats * n_envs * n_steps / wall,
    }


def machine() -> dict[str, Any]:
    import numba

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if "model name" in line)
    except (OSError, StopIteration):
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "numba_threads": numba.get_num_threads(),
        "python": platform.python_version(),
        "numba": numba.__version__,
        "load_average_1min": os.getloadavg()[0],
    }


def _waves_rows(args: Options) -> list[dict[str, Any]]:
    """Physics rate without and with waves, side by side (`_side_by_side`)."""
    from auv_gym.ocean.waves import WaveConfig

    waves = WaveConfig()  # sea state 4, default components and update interval
    print(
        f"\nWaves: sea state 4 ({waves.spectrum}, {waves.components} components, field "
        f"refreshed every {waves.update_interval:g} s) beside no waves"
    )
    deep = {"path_offset": (0.0, 0.0, 110.0)}  # waves act below the surface: the helix moved down
    return _side_by_side(args, [args.waves_n], {"waves": waves}, ("no_waves", "waves"), deep)


# The vehicle as built (benchmarks/scenarios.toml as_built_helix): propeller and fins, the
# navigation suite with its Kalman filter, the ocean preset (waves, sheared and random currents).
AS_BUILT = {"disturbance": "ocean", "actuator": "realistic", "sensors": "typical_kalman"}


def _as_built_rows(args: Options) -> list[dict[str, Any]]:
    """Physics rate of the paper configuration and the as-built one, side by side."""
    print(
        "\nThe vehicle as built (ocean preset, propeller and fins, 'typical_kalman' navigation) "
        "beside the paper configuration"
    )
    return _side_by_side(args, [args.as_built_n], AS_BUILT, ("paper", "as_built"))


def _guidance_rows(args: Options) -> list[dict[str, Any]]:
    """Physics rate of the as-built configuration with the virtual point moved by the plant's
    law and by the guidance computer (docs/model.md §14.9), side by side."""
    print(
        "\nThe vehicle as built with its guidance computer (virtual_point='estimate') beside "
        "the plant's law"
    )
    computer = {"sensors": {"preset": "typical_kalman", "virtual_point": "estimate"}}
    return _side_by_side(args, [args.guidance_n], computer, ("plant_law", "computer"), AS_BUILT)


def _plant_rows(args: Options) -> list[dict[str, Any]]:
    """Physics rate of the 5-DOF plant and the 6-DOF one (docs/model.md §15), side by side."""
    print("\nThe 6-DOF plant (roll, Fossen's REMUS 100 hull) beside the 5-DOF, paper configuration")
    return _side_by_side(args, [args.plant_n], {"plant": "6dof"}, ("5dof", "6dof"))


@dataclass
class Options:
    """The command line of `auv-gym speed vector`."""

    sizes: tuple[int, ...] = option(SIZES, "numbers of vehicles of the throughput table", nargs="+")
    seconds: float = option(4.0, "timed wall clock per size")
    max_time: float = option(10.0, "episode length [s]; short so that autoresets happen")
    waves_n: int = option(
        4096,
        "vehicles of the side-by-side run with waves (sea state 4, default components); 0 skips it",
    )
    as_built_n: int = option(
        4096, "vehicles of the side-by-side run of the as-built configuration; 0 skips it"
    )
    plant_n: int = option(
        4096, "vehicles of the side-by-side run of the 5-DOF and 6-DOF plants; 0 skips it"
    )
    guidance_n: int = option(
        4096,
        "vehicles of the side-by-side run of the as-built configuration with and without its "
        "guidance computer; 0 skips it",
    )
    memory_n: int = option(MEMORY_N, "vehicles of the peak-memory run; 0 skips it")
    ppo_envs: tuple[int, ...] = option(
        (64,), "n_envs of the SB3 collection runs; none skips them", nargs="*"
    )
    ppo_steps: int = option(128, "n_steps per rollout")
    ppo_repeats: int = option(3, "timed collect_rollouts calls per run")
    threads: tuple[int, ...] = option(
        (2, 1), "numba thread counts of the throughput table", nargs="+"
    )
    actuators: tuple[str, ...] = option(
        ("paper", "realistic"),
        "actuator models of the throughput table, side by side",
        choices=("paper", "fins", "realistic"),
        nargs="+",
    )
    sensor_sizes: tuple[int, ...] = option(
        (4096,),
        "N of the side-by-side rows without and with the 'typical' sensor model "
        "(docs/model.md §14); none skips them",
        nargs="*",
    )
    quick: bool = option(False, "tiny budget (smoke test)")
    json: str | None = option(None, "also write the results to this file")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.vector"), __doc__, negatable=False
    )
    if args.json:  # written after the benchmark: refused now, not after minutes of timing
        with usage_errors(parser):
            writable_location(args.json, "--json", folder=False)
    if args.quick:
        args.sizes, args.seconds, args.memory_n, args.max_time = (1, 64), 0.05, 1024, 0.5
        args.waves_n = args.as_built_n = args.plant_n = args.guidance_n = 64
        args.threads, args.sensor_sizes = (1,), (64,)
        args.ppo_envs, args.ppo_steps, args.ppo_repeats = (4,), 8, 1

    info = machine()
    print(
        f"{info['cpu']}, {info['cores']} cores, numba threads ≤ {info['numba_threads']}, "
        f"load average {info['load_average_1min']:.2f} at start"
    )
    results: dict[str, Any] = {"machine": info, "vector": [], "ppo": []}

    print(
        f"\nAUVPath3DVectorEnv, default physics, white noise ±35, NEXT_STEP autoreset "
        f"(max_time {args.max_time:g} s)"
    )
    print(
        f"{'N':>7} {'actuator':>9} {'threads':>7} {'physics steps/s':>16} "
        f"{'control steps/s':>16} {'real-time ×':>12} {'ms/step':>9} {'glue':>6} "
        f"{'resets':>7}"
    )
    runs = ((t, n, a) for t in args.threads for n in args.sizes for a in args.actuators)
    for threads, n, actuator in runs:
        r = measure_vector(n, args.seconds, args.max_time, threads, actuator=actuator)
        results["vector"].append(r)
        print(
            f"{n:>7} {actuator:>9} {r['threads']:>7} {r['physics_steps_per_s']:>16,.0f} "
            f"{r['vehicle_steps_per_s']:>16,.0f} "
            f"{r['real_time_factor']:>12,.0f} {r['ms_per_batch_step']:>9.3f} "
            f"{r['glue_fraction']:>6.1%} {r['autoresets']:>7}"
        )

    if args.waves_n > 0:
        results["waves"] = _waves_rows(args)
    if args.sensor_sizes:
        results["sensors"] = _sensor_rows(args)
    if args.as_built_n > 0:
        results["as_built"] = _as_built_rows(args)
    if args.guidance_n > 0:
        results["guidance"] = _guidance_rows(args)
    if args.plant_n > 0:
        results["plant"] = _plant_rows(args)

    if args.memory_n > 0:
        mem = _fresh_process(f"measure_memory({args.memory_n})")
        results["memory"] = mem
        mib = 2.0**20
        print(
            f"\nN = {mem['n']:,}: peak RSS {mem['peak_bytes'] / mib:,.0f} MiB, growth over "
            f"the imported+compiled process {mem['growth_bytes'] / mib:,.0f} MiB (target < "
            f"1024); reset {mem['reset_s']:.2f} s, step {1e3 * mem['step_s']:.1f} ms"
        )

    if args.ppo_envs:
        print(f"\nSB3 PPO collect_rollouts (MlpPolicy, torch 1 thread, n_steps {args.ppo_steps})")
        print(f"{'backend':<12} {'n_envs':>7} {'timesteps/s':>12}")
        for n_envs in args.ppo_envs:
            for backend in ("adapter", "DummyVecEnv"):
                r = _fresh_process(
                    f"measure_ppo_collection({n_envs}, {args.ppo_steps}, "
                    f"{args.ppo_repeats}, {backend!r})"
                )
                results["ppo"].append(r)
                print(f"{backend:<12} {n_envs:>7} {r['timesteps_per_s']:>12,.0f}")
    results["machine"]["load_average_1min_end"] = os.getloadavg()[0]
    if args.json:
        write_json(args.json, results, indent=2)
    return results


if __name__ == "__main__":
    main()
