"""`auv-gym compile`: compile and cache the simulation kernels once, saying how far it is.

numba compiles each kernel on its first use after an install or an edit of the physics, and
caches it on disk (`auv_gym.support.numba_cache`); a kernel is compiled per plant and set of
options a configuration uses (`auv_gym.sim.fleet`). The set-up (scripts/setup.sh) runs this
step for what the main job flies: its scenarios with every classical controller, and the RL
task's agent observation, for one second each. ``--all`` adds every other benchmark scenario
(the 6-DOF plant, the torpedo, the vehicle as built with its navigation filter): the test
script runs it, and a configuration it leaves out compiles on its first episode, once. Run
again, it returns at once unless a source changed.

    auv-gym compile             # or: python -m benchmarks.runner.compile_kernels
    auv-gym compile --all
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

__all__ = ["main"]

POLICIES = ("fbsm", "backstepping", "pid_los")  # every classical kernel
# The scenarios of the main job (scripts/main.sh): what the set-up compiles.
MAIN_JOB_SCENARIOS = ("paper", "current", "fins", "waypoints", "storm", "realistic_actuators")
# Measured on 2 cores (fresh cache, 2026-12-03): see docs/performance.md "Compiling".
FIRST_RUN = {False: "about 2 minutes on 2 cores", True: "about 2.5 minutes on 2 cores"}


@dataclass
class Options:
    """The options of `auv-gym compile`."""

    force: bool = option(False, "compile even when the cache is marked current")
    all: bool = option(False, "every benchmark scenario, not only the main job's")
    quiet: bool = option(False, "no progress bar")


def _packages() -> tuple[Path, Path]:
    import auv_gym
    import controllers

    return Path(auv_gym.__file__).parent, Path(controllers.__file__).parent


def compile_kernels(progress: bool = True, every_scenario: bool = False) -> float:
    """Fly every classical controller on the main job's scenarios (``every_scenario``: on all of
    them, and the 6-DOF plant and the vehicle as built in a batch) and the RL task for 1 s; the
    wall time [s] it took."""
    import gymnasium as gym
    import numpy as np

    import controllers
    from auv_gym.rollout import evaluate
    from benchmarks.catalog.scenarios import load_scenarios
    from controllers.registry import NoFiveDofModelError

    scenarios = [
        s for s in load_scenarios().values() if every_scenario or s.name in MAIN_JOB_SCENARIOS
    ]
    jobs = [(s, p) for s in scenarios for p in POLICIES]
    start = time.perf_counter()
    bar = None
    if progress:
        from tqdm.auto import tqdm

        # No time estimate: the first configurations compile nearly every kernel and the rest
        # reuse them, so a rate from the first ones would predict hours (it once said 4 h 51 min).
        bar = tqdm(
            total=len(jobs) + 1,
            desc="compiling kernels",
            unit="configuration",
            file=sys.stderr,
            bar_format="{desc}: {n}/{total} configurations flown, {elapsed} elapsed{postfix}",
        )
    ticking = _Ticker(bar) if bar is not None else None  # the clock moves during a compile
    for scenario, name in jobs:
        if bar is not None:
            bar.set_postfix_str(f"{scenario.name}, {name}")
        env = {**scenario.env, "max_time": 1.0}
        try:
            policy = controllers.make(name, env=env, **scenario.controller)
        except NoFiveDofModelError:  # FBSM on a vehicle without a 5-DOF model: never flown
            pass
        else:
            evaluate(policy, [0], transient=0.0, **env)
        if bar is not None:
            bar.update()
    # The env API's own call signatures: float32 and float64 actions, one env and a batch.
    for dtype in (np.float32, np.float64):
        envs = gym.make_vec("AUVPath3DPreview-v0", num_envs=2, observation="preview_integral")
        envs.reset(seed=0)
        envs.step(np.zeros((2, 3), dtype=dtype))
        envs.close()
        for plant in ("5dof", "6dof") if every_scenario else ("5dof",):
            env = gym.make("AUVPath3D-v0", plant=plant)
            env.reset(seed=0)
            env.step(np.zeros(3, dtype=dtype))
            env.close()
    # The 6-DOF plant in a batch and on the vehicle as built (the suite's --plant, the tests).
    as_built = {"disturbance": "ocean", "actuator": "realistic", "sensors": "typical_kalman"}
    for env in ({"plant": "6dof"}, {"plant": "6dof", **as_built}) if every_scenario else ():
        envs = gym.make_vec("AUVPath3D-v0", num_envs=2, **env)
        envs.reset(seed=0)
        envs.step(np.zeros((2, 3)))
        envs.close()
        evaluate(controllers.make("pid_los", env=env), [0], transient=0.0, max_time=1.0, **env)
    if ticking is not None:
        ticking.stop()
    if bar is not None:
        bar.update()
        bar.close()
    return time.perf_counter() - start


class _Ticker:
    """Redraws a progress bar every few seconds from a thread: one kernel compiles for minutes
    with no update, and a bar whose elapsed time stands still reads as hung."""

    def __init__(self, bar: Any, every: float = 5.0) -> None:
        import threading

        self._bar, self._every, self._done = bar, every, threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._done.wait(self._every):
            self._bar.refresh()

    def stop(self) -> None:
        self._done.set()
        self._thread.join()


def main(argv: Sequence[str] | None = None) -> int:
    from auv_gym.support.numba_cache import kernels_are_cached, mark_kernels_cached

    opts, _ = parse_options(
        Options, argv, program_name("benchmarks.runner.compile_kernels"), __doc__, negatable=False
    )
    packages = _packages()
    scope = "every scenario's" if opts.all else "the main job's"
    if kernels_are_cached(*packages) and _scope_marked(opts.all) and not opts.force:
        print(f"auv-gym compile: {scope} kernels are compiled and current", file=sys.stderr)
        return 0
    print(
        f"auv-gym compile: compiling {scope} simulation kernels once ({FIRST_RUN[opts.all]}; "
        "cached for every later run, recompiled after an edit of the physics)",
        file=sys.stderr,
    )
    seconds = compile_kernels(progress=not opts.quiet, every_scenario=opts.all)
    mark_kernels_cached(*packages)
    _mark_scope(opts.all)
    print(f"auv-gym compile: kernels compiled and cached in {seconds:.0f} s", file=sys.stderr)
    return 0


def _scope_marker() -> Path | None:
    """The file that records that ``--all`` ran to its end with the current sources (beside
    the kernels of `auv_gym.sim`), or None without a cache directory."""
    from auv_gym.support.numba_cache import NUMBA_MARKER, cache_directory, sources_digest

    auv_gym_dir, controllers_dir = _packages()
    folder = cache_directory(auv_gym_dir / "sim")
    if folder is None:
        return None
    digest = sources_digest(auv_gym_dir, controllers_dir, containing=NUMBA_MARKER)
    return Path(folder) / f".compiled-all-{digest[:16]}"


def _scope_marked(every_scenario: bool) -> bool:
    """Whether the scope asked for is compiled: the main job's whenever the packages are
    marked current, every scenario's only after a ``--all`` run with the same sources."""
    if not every_scenario:
        return True
    marker = _scope_marker()
    return marker is not None and marker.is_file()


def _mark_scope(every_scenario: bool) -> None:
    marker = _scope_marker() if every_scenario else None
    if marker is not None:
        marker.touch()


if __name__ == "__main__":
    sys.exit(main())
