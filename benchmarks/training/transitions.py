"""The transitions an off-policy jump start flew, handed to the next phase's replay buffer.

A SAC (or TQC) jump start (`benchmarks.training.dagger_sac`) stores every transition it flies in
the model's replay buffer as SAC's own rollouts would (raw observation and next observation,
the action taken in the agent's normalised action space [−1, 1]³, raw reward, ``dones`` and
``timeouts``). The run writes them as `TRANSITIONS_FILE` beside its agents, a schedule copies
that file into the selected agent folder the next phase starts from
(`benchmarks.training.schedule`), and `benchmarks.training.warm_start` fills the new model's
buffer with them.

The file is an .npz of plain arrays read with ``allow_pickle=False``, not SB3's pickled buffer
(`model.save_replay_buffer`): an agent folder is data that auv-gym never unpickles
(docs/usage.md "Trusting agent files"), and a buffer of another shape (another ``n_envs`` or
``buffer_size`` in the next phase) is laid out anew anyway.

A buffer holds one stream of consecutive steps per vehicle (its column). The file keeps them as
one flat stream with ``breaks``: after such a row the next row is not the same vehicle's next
step (the end of a column, the end of a round whose episodes the next round restarted). Laid
into a buffer, a break that is not an episode end becomes ``timeouts`` without ``dones``: SB3's
targets then bootstrap from the row's own next observation (what SAC's n-step buffer does at
its newest row), so no n-step return runs across two streams.

A jump start also knows the expert's command in every state it stored (DAgger labels each
visited state; a dataset's action is the expert's): ``labels``, the expert's action in the
agent's normalised action space [−1, 1]³, one per transition, ride along when the buffer carries
them (`attach_labels`; a file without them is read as before). A SAC run that fine-tunes with a
behaviour-cloning term (`benchmarks.training.demo_regularization`) reads them; laid into a
replay buffer they are ignored.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.support.files import write_atomic

__all__ = [
    "LABELS",
    "TRANSITIONS_FILE",
    "attach_labels",
    "buffer_stream",
    "cut_streams",
    "fill_buffer",
    "read_transitions",
    "write_transitions",
]

TRANSITIONS_FILE = "replay_transitions.npz"
ARRAYS = ("observations", "next_observations", "actions", "rewards", "dones", "timeouts", "breaks")
LABELS = "labels"  # optional: the expert's action per transition, in [-1, 1]^3 (module doc)


def attach_labels(buffer: Any) -> np.ndarray:
    """Give ``buffer`` a ``labels`` array shaped like its actions, NaN (no label) until
    written: `fill_buffer` and the jump start's recorder fill it, `buffer_stream` hands it on."""
    buffer.labels = np.full(buffer.actions.shape, np.nan, dtype=np.float32)
    return buffer.labels


def cut_streams(buffer: Any) -> None:
    """Mark the newest row of ``buffer`` as the end of every vehicle's stream (a timeout where
    the episode goes on): the next rows, from reset envs, do not continue it."""
    if buffer.pos == 0 and not buffer.full:
        return
    row = (buffer.pos - 1) % buffer.buffer_size
    buffer.timeouts[row] = np.maximum(buffer.timeouts[row], 1.0 - buffer.dones[row])


def buffer_stream(buffer: Any) -> dict[str, np.ndarray]:
    """The transitions of an SB3 `ReplayBuffer` as one flat stream (module doc): column by
    column, oldest row first; with ``labels`` when the buffer carries a label for every one."""
    rows = np.arange(buffer.pos)
    if buffer.full:
        rows = (np.arange(buffer.buffer_size) + buffer.pos) % buffer.buffer_size
    dones = buffer.dones[rows].astype(bool)
    cut = buffer.timeouts[rows].astype(bool) & ~dones  # `cut_streams`
    breaks = cut.copy()
    if len(rows):
        breaks[-1] = True  # a column's last row: the next column is another vehicle

    def flat(array: np.ndarray) -> np.ndarray:  # (rows, n_envs, ...) -> (n_envs * rows, ...)
        return np.swapaxes(array, 0, 1).reshape(-1, *array.shape[2:])

    stream = {
        "observations": flat(buffer.observations[rows]),
        "next_observations": flat(buffer.next_observations[rows]),
        "actions": flat(buffer.actions[rows]),
        "rewards": flat(buffer.rewards[rows]),
        "dones": flat(dones),
        "timeouts": flat(buffer.timeouts[rows].astype(bool) & dones),
        "breaks": flat(breaks),
    }
    labels = getattr(buffer, LABELS, None)
    if labels is not None and np.all(np.isfinite(labels[rows])):
        stream[LABELS] = flat(labels[rows])
    return stream


def fill_buffer(buffer: Any, stream: Mapping[str, np.ndarray]) -> int:
    """Append a flat stream to an SB3 `ReplayBuffer`: cut into ``n_envs`` consecutive chunks,
    one per column (the oldest ``len % n_envs`` transitions, fewer than ``n_envs``, and whatever
    exceeds the buffer's capacity are left out); the stream's ``labels`` too where both it and
    the buffer carry them (`attach_labels`). Returns the transitions added."""
    n = buffer.n_envs
    total = len(stream["rewards"])
    rows = min(total // n, buffer.buffer_size)
    if rows == 0:
        return 0
    first = total - rows * n

    def columns(key: str) -> np.ndarray:  # (rows * n, ...) -> (rows, n, ...)
        array = np.asarray(stream[key])[first:]
        return np.swapaxes(array.reshape(n, rows, *array.shape[1:]), 0, 1)

    dones = columns("dones").astype(bool)
    breaks = columns("breaks").astype(bool)
    breaks[-1] = True  # each chunk's end: the next chunk is another stream
    index = (buffer.pos + np.arange(rows)) % buffer.buffer_size
    buffer.observations[index] = columns("observations")
    buffer.next_observations[index] = columns("next_observations")
    buffer.actions[index] = columns("actions")
    buffer.rewards[index] = columns("rewards")
    buffer.dones[index] = dones
    buffer.timeouts[index] = (columns("timeouts").astype(bool) & dones) | (breaks & ~dones)
    if LABELS in stream and getattr(buffer, LABELS, None) is not None:
        buffer.labels[index] = columns(LABELS)
    buffer.full = buffer.full or buffer.pos + rows >= buffer.buffer_size
    buffer.pos = int((buffer.pos + rows) % buffer.buffer_size)
    return rows * n


def write_transitions(path: Path, buffer: Any, obs_names: Sequence[str]) -> Path:
    """`TRANSITIONS_FILE` of ``buffer`` (atomically), naming the observation entries."""
    stream = buffer_stream(buffer)
    return write_atomic(
        path, lambda fh: np.savez(fh, obs_names=np.array(list(obs_names)), **stream)
    )


def read_transitions(
    path: Path, obs_names: Sequence[str], action_dim: int, where: str
) -> dict[str, np.ndarray]:
    """The stream of a `TRANSITIONS_FILE`, checked for an agent observing ``obs_names`` with
    ``action_dim`` actions, with its ``labels`` where it has them; a one-line ValueError naming
    ``where`` and the file otherwise."""
    at = f"{where}: {path}"
    try:
        with np.load(path, allow_pickle=False) as data:
            values = {key: np.asarray(data[key]) for key in data.files}
    except Exception as exc:
        raise ValueError(f"{at} is unreadable: {' '.join(str(exc).split())}") from None
    missing = [key for key in (*ARRAYS, "obs_names") if key not in values]
    if missing:
        raise ValueError(f"{at} lacks {missing} (written by an off-policy jump start)")
    theirs = [str(name) for name in values["obs_names"]]
    if theirs != list(obs_names):
        raise ValueError(
            f"{at}: its transitions observe {len(theirs)} entries, this run's agent "
            f"{len(obs_names)}: they were flown with another observation"
        )
    total = len(values["rewards"])
    shapes: dict[str, tuple[int, ...]] = {
        "observations": (total, len(theirs)),
        "next_observations": (total, len(theirs)),
        "actions": (total, action_dim),
    }
    for key in ARRAYS:
        wanted = shapes.get(key, (total,))
        if values[key].shape != wanted:
            raise ValueError(f"{at}: {key} has shape {values[key].shape}, expected {wanted}")
        if key in shapes or key == "rewards":
            if not np.all(np.isfinite(values[key])):
                raise ValueError(f"{at}: {key} is not finite")
    if np.any(np.abs(values["actions"]) > 1.0 + 1e-5):  # float rounding of the rescaling
        raise ValueError(f"{at}: actions outside the normalised action space [-1, 1]")
    keys = ARRAYS
    if LABELS in values:
        labels = values[LABELS]
        if labels.shape != (total, action_dim):
            raise ValueError(
                f"{at}: labels have shape {labels.shape}, expected {(total, action_dim)}"
            )
        if not np.all(np.isfinite(labels)) or np.any(np.abs(labels) > 1.0 + 1e-5):
            raise ValueError(f"{at}: labels are not finite actions in [-1, 1]")
        keys = (*ARRAYS, LABELS)
    return {key: values[key] for key in keys}
