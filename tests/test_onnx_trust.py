"""An exported agent's files are not trusted (docs/usage.md, "Policies that leave Python"): the
hash covers every byte onnxruntime loads, sizes are capped before anything is allocated, the
contract is checked against itself, the graph and the env, every output is checked, and no
onnxruntime session the project creates sends telemetry. Each case: one line naming the file."""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import controllers
from auv_gym.sim.observation import ObservationConfig
from auv_gym.vehicle.actuators import ActuatorParams
from benchmarks.catalog.policies import AGENTS_DIR, check_policy_spec
from controllers.actuator_allocation import Allocation
from controllers.allocation import ALLOCATION_FIELDS
from controllers.onnx_contract import MAX_GRAPH_BYTES, read_contract
from controllers.onnx_export import write_export
from controllers.onnx_file import MAX_TENSOR_ELEMENTS, scan_model

onnx = pytest.importorskip("onnx")
# onnxruntime is not imported here (that alone would write its telemetry), only by the project
pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("onnxruntime") is None, reason="needs onnxruntime"
)

ROOT = Path(__file__).resolve().parents[1]


def _copy(tmp_path: Path, agent: str = "ppo_generalist") -> Path:
    """A copy of a shipped export; its .onnx file."""
    for name in ("policy.onnx", "policy.json"):
        shutil.copy(AGENTS_DIR / agent / name, tmp_path / name)
    return tmp_path / "policy.onnx"


def _edit_contract(onnx_file: Path, edit: Callable[[dict], None]) -> None:
    file = onnx_file.with_suffix(".json")
    data = json.loads(file.read_text())
    edit(data)
    file.write_text(json.dumps(data))


def _edit_graph(onnx_file: Path, edit: Callable[[object], None]) -> None:
    """Edit the model in place and record its new SHA-256 in the contract, as a forger would."""
    model = onnx.load(onnx_file)
    edit(model)
    data = model.SerializeToString()
    onnx_file.write_bytes(data)
    _edit_contract(onnx_file, lambda c: c.update(onnx_sha256=hashlib.sha256(data).hexdigest()))


def _after_action(op: str, value: object, extra: Callable | None = None) -> Callable:
    """An edit that ends the graph in ``action = op(action, value)``."""
    from onnx import helper, numpy_helper

    def edit(model) -> None:
        for node in model.graph.node:
            node.output[:] = ["raw_action" if o == "action" else o for o in node.output]
        constant = numpy_helper.from_array(np.asarray(value, np.float32), "forged")
        model.graph.initializer.append(constant)
        second = "forged"
        if extra is not None:
            second = extra(model)
        model.graph.node.append(helper.make_node(op, ["raw_action", second], ["action"]))

    return edit


def _one_line(error: pytest.ExceptionInfo, *parts: str) -> None:
    text = str(error.value)
    assert len(text.splitlines()) == 1, text
    for part in parts:
        assert part in text, text


def test_make_onnx_with_a_non_path_is_a_clear_error():
    """Was: a bare TypeError from pathlib."""
    with pytest.raises(TypeError) as error:
        controllers.make("onnx", path=123)
    _one_line(error, "controllers.make('onnx'): path must be", "got int 123")
    assert isinstance(error.value, ValueError)  # caught as a usage error by the CLIs too


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (lambda c: c.update(actuator="foo"), "actuator 'foo' is not one of ['paper', 'fins'"),
        (lambda c: c.update(allocated="false"), "'allocated' is 'false', not true/false"),
        (lambda c: c.update(plant="7dof"), "plant '7dof' is not one of ['5dof', '6dof']"),
        (lambda c: c["state"].update(size=3), "state size 3, the graph it describes keeps 4"),
        (lambda c: c.update(format_version=1), "format version 1, this auv-gym reads 2: re-export"),
        (
            lambda c: c["residual"].update(base="nope"),
            "residual base 'nope' is not a classical controller",
        ),
        (
            lambda c: c.update(actuator="fins"),
            "its env (AUVPath3DSpeedLimit-v0, env_kwargs) has actuator 'paper', the contract says",
        ),
        (
            lambda c: c.update(control_period_s=0.1),
            "has control period 0.05, the contract says 0.1",
        ),
    ],
)
def test_a_contract_that_contradicts_itself_is_refused(tmp_path, edit, expected):
    """Was: actuator "foo" accepted, allocated "false" read as true."""
    onnx_file = _copy(tmp_path, "ppo_residual")
    _edit_contract(onnx_file, edit)
    with pytest.raises(ValueError) as error:
        controllers.make("onnx", path=str(onnx_file))
    _one_line(error, f"ONNX contract {onnx_file.with_suffix('.json')}", expected)


def test_a_contract_the_graph_contradicts_is_refused(tmp_path):
    """A contract edited consistently (the fins named in the env and the actuator) still names
    an env the graph was not built for: the graph's metadata, which the hash covers, says so."""
    onnx_file = _copy(tmp_path, "ppo_as_built")  # no allocation stage

    def edit(c):
        c.update(actuator="fins", env_kwargs={**c["env_kwargs"], "actuator": "fins"})

    _edit_contract(onnx_file, edit)
    with pytest.raises(ValueError) as error:
        read_contract(onnx_file)
    _one_line(error, "says env_kwargs {'surge_limit': 'vehicle',", "was built for {'surge_limit'")


def test_the_graph_inputs_and_outputs_are_checked_against_the_contract(tmp_path):
    """Was: the contract's memory size was not checked against the graph (a 62-line traceback
    after other policies' episodes ran)."""
    onnx_file = _copy(tmp_path, "ppo_residual")

    def any_state(model) -> None:  # state: (n, 4) → (n, s), which onnxruntime would run
        model.graph.input[1].type.tensor_type.shape.dim[1].dim_param = "s"

    _edit_graph(onnx_file, any_state)
    with pytest.raises(ValueError) as error:
        controllers.make("onnx", path=str(onnx_file))
    _one_line(error, f"ONNX graph {onnx_file} takes ('state', ['n', 's'], 'tensor(float)'), its")
    assert "says ('state', ['n', 4], 'tensor(float)')" in str(error.value)

    onnx_file = _copy(tmp_path)

    def one_vehicle(model) -> None:  # a graph that takes one vehicle at a time
        model.graph.input[0].type.tensor_type.shape.dim[0].dim_value = 1

    _edit_graph(onnx_file, one_vehicle)
    with pytest.raises(ValueError) as error:
        controllers.make("onnx", path=str(onnx_file))
    _one_line(error, "takes ('observation', [1, 49], 'tensor(float)')", "['n', 49]")


def test_external_data_is_refused(tmp_path):
    """Was: weights kept beside the graph were not covered by the SHA-256 (edited to NaN after
    export, they loaded unchecked)."""
    onnx_file = _copy(tmp_path)
    model = onnx.load(onnx_file)
    onnx.save_model(
        model,
        onnx_file,
        save_as_external_data=True,
        all_tensors_to_one_file=True,
        location="weights.bin",
        size_threshold=0,
    )
    data = onnx_file.read_bytes()
    _edit_contract(onnx_file, lambda c: c.update(onnx_sha256=hashlib.sha256(data).hexdigest()))
    assert (tmp_path / "weights.bin").stat().st_size > 10_000  # the network's weights
    with pytest.raises(ValueError) as error:
        read_contract(onnx_file)
    _one_line(error, f"ONNX graph {onnx_file} keeps tensors as external data")


def test_sizes_are_capped_before_anything_is_read_or_allocated(tmp_path):
    """Was: a 30-GB file gave a MemoryError, a 2^40-element tensor a traceback."""
    onnx_file = _copy(tmp_path)
    with onnx_file.open("r+b") as fh:  # sparse: no disk space used
        fh.truncate(30 * 10**9)
    start = time.perf_counter()
    with pytest.raises(ValueError) as error:
        controllers.make("onnx", path=str(onnx_file))
    assert time.perf_counter() - start < 1.0  # refused by its size, not read
    _one_line(error, f"ONNX graph {onnx_file} is 30,000,000,000 bytes, more than the 268,435,456")
    assert MAX_GRAPH_BYTES == 2**28

    onnx_file = _copy(tmp_path)
    from onnx import TensorProto

    def huge(model) -> None:  # declared 2^40 elements, no data: allocated by whoever trusts it
        tensor = TensorProto(name="huge", data_type=TensorProto.FLOAT, dims=[2**20, 2**20])
        model.graph.initializer.append(tensor)

    _edit_graph(onnx_file, huge)
    with pytest.raises(ValueError) as error:
        read_contract(onnx_file)
    _one_line(error, "a stored tensor of 1,099,511,627,776 or more elements exceeds 67,108,864")
    assert MAX_TENSOR_ELEMENTS == 2**26


def test_a_node_that_allocates_too_much_is_one_line(tmp_path):
    """A 2^29-element tensor built while running (2 GiB: above onnxruntime's 1-GiB constant
    folding and the sessions' 512-MiB arena) is refused by the arena, not allocated."""
    from onnx import helper, numpy_helper

    def big(model) -> str:
        shape = numpy_helper.from_array(np.array([2**29], np.int64), "big_shape")
        model.graph.initializer.append(shape)
        model.graph.node.append(helper.make_node("ConstantOfShape", ["big_shape"], ["big"]))
        model.graph.node.append(helper.make_node("ReduceSum", ["big"], ["big_sum"], keepdims=0))
        return "big_sum"

    onnx_file = _copy(tmp_path)
    _edit_graph(onnx_file, _after_action("Add", 0.0, big))
    policy = controllers.make("onnx", path=str(onnx_file))
    with pytest.raises(ValueError) as error:
        policy.predict(np.zeros(49, np.float32))
    _one_line(error, f"ONNX graph {onnx_file} failed to run: ", "ConstantOfShape")


@pytest.mark.parametrize(
    ("op", "value", "expected"),
    [
        ("Mul", np.nan, "gave action row 0 [nan, nan, nan]: not finite"),
        ("Add", 1e6, "gave action row 0 [{shifted}]: outside [-1, 1]"),
    ],
)
def test_every_output_is_checked(tmp_path, op, value, expected):
    """Was: NaN reached the env, ±1e6 actions were recorded."""
    onnx_file = _copy(tmp_path)
    observation = np.zeros((2, 49), np.float32)
    commands = controllers.make("onnx", path=str(onnx_file)).predict(observation)[0]
    _edit_graph(onnx_file, _after_action(op, value))
    policy = controllers.make("onnx", path=str(onnx_file))
    with pytest.raises(ValueError) as error:
        policy.predict(observation)
    shifted = ", ".join(str(float(np.float32(c) + np.float32(value))) for c in commands[0])
    _one_line(error, f"ONNX graph {onnx_file} {expected.format(shifted=shifted)}")


def test_the_scan_reads_the_shipped_graphs_metadata():
    data = (AGENTS_DIR / "ppo_generalist" / "policy.onnx").read_bytes()
    props = scan_model(data, "x")
    assert props == {p.key: p.value for p in onnx.load_from_string(data).metadata_props}
    with pytest.raises(ValueError, match="x is not a well-formed ONNX model"):
        scan_model(data[: len(data) // 2], "x")


def test_write_export_writes_both_files_or_neither(tmp_path, monkeypatch):
    """Was: a failed contract write left a new .onnx without its contract."""
    from controllers import onnx_export

    target = tmp_path / "agent.onnx"
    write_export(target, b"graph one", {"contract": 1})
    assert target.read_bytes() == b"graph one"

    with pytest.raises(TypeError, match="keys must be"):  # a contract JSON cannot hold
        write_export(target, b"graph two", {("a", "b"): 2})
    assert target.read_bytes() == b"graph one"

    real_replace = os.replace

    def replace(source, destination):  # the contract's rename fails (a full or read-only disk)
        if str(destination).endswith(".json"):
            raise OSError("no space left on device")
        real_replace(source, destination)

    monkeypatch.setattr(onnx_export.os, "replace", replace)
    with pytest.raises(OSError, match="no space"):
        write_export(target, b"graph three", {"contract": 3})
    with pytest.raises(OSError, match="no space"):
        write_export(tmp_path / "new.onnx", b"graph", {"contract": 4})
    monkeypatch.undo()
    assert target.read_bytes() == b"graph one"  # the previous graph is back
    assert json.loads(target.with_suffix(".json").read_text()) == {"contract": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["agent.json", "agent.onnx"]


def test_the_allocation_reads_the_actuator_settings_it_lists():
    """`ALLOCATION_FIELDS` is what an export for the propeller and fins records and checks:
    each listed field changes the allocation, each other field does not."""
    names = ObservationConfig.from_spec("preview_integral").names
    rng = np.random.default_rng(4)
    obs = rng.normal(0.0, 1.0, (400, len(names))).astype(np.float32)
    obs[:, names.index("u")] = rng.uniform(-0.5, 2.5, 400)
    commands = rng.uniform(-1.2, 1.2, (400, 3))
    reference = Allocation(names, "realistic", actuator_params=ActuatorParams())
    want = reference.allocate(commands, obs)
    read = []
    for f in dataclasses.fields(ActuatorParams):
        value = getattr(ActuatorParams(), f.name)
        changed = ActuatorParams().replace(**{f.name: 1.0 if value == np.inf else 0.9 * value})
        allocation = Allocation(names, "realistic", actuator_params=changed)
        got = allocation.allocate(commands, obs)
        if allocation.fin_gain != reference.fin_gain or any(
            not np.array_equal(a, b) for a, b in zip(got, want, strict=True)
        ):
            read.append(f.name)
    assert tuple(read) == ALLOCATION_FIELDS


def _run_onnx_session(home, import_onnxruntime_first):
    """Run one ONNX policy of the project in a fresh interpreter whose home folder is `home`;
    return ORT_DISABLE_TELEMETRY as that interpreter saw it and the telemetry files written."""
    path = AGENTS_DIR / "ppo_generalist" / "policy.onnx"
    script = (
        "import os\n"
        + ("import onnxruntime\n" if import_onnxruntime_first else "")
        + "import numpy as np\n"
        "import controllers\n"
        "from benchmarks.catalog.policies import check_policy_spec\n"
        f"policy = controllers.make('onnx', path={str(path)!r})\n"
        "policy.predict(np.zeros(49, np.float32))\n"
        f"check_policy_spec({'onnx:' + str(path)!r})\n"
        "print(os.environ.get('ORT_DISABLE_TELEMETRY'))\n"
    )
    env = {
        k: v for k, v in os.environ.items() if k not in ("ORT_DISABLE_TELEMETRY", "XDG_CACHE_HOME")
    }
    env["HOME"] = str(home)
    done = subprocess.run(
        [sys.executable, "-c", script],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    written = sorted(
        str(p.relative_to(home))
        for p in Path(home).rglob("*")
        if p.is_file() and ("Microsoft" in p.parts or ".onnxruntime" in p.parts)
    )
    return done.stdout.split(), written


def test_the_project_imports_onnxruntime_with_telemetry_disabled(tmp_path):
    """Whatever the installed onnxruntime does, every session the project opens runs with
    ORT_DISABLE_TELEMETRY=1 and writes no onnxruntime telemetry under the home folder."""
    seen, written = _run_onnx_session(tmp_path, import_onnxruntime_first=False)
    assert seen == ["1"]
    assert written == []


def test_telemetry_check_can_see_what_onnxruntime_writes(tmp_path):
    """Control for the test above: onnxruntime ≥ 1.29, imported before the project, writes a
    device id under the home folder on machines where its telemetry is active (not on every
    machine: some builds and sandboxes never write it, and the control then has nothing to show)."""
    _, written = _run_onnx_session(tmp_path, import_onnxruntime_first=True)
    if not written:
        pytest.skip("this machine's onnxruntime writes no telemetry files even when enabled")
    assert any(Path(name).name == "deviceid" for name in written), written


def test_compare_refuses_a_forged_export_before_any_episode(tmp_path):
    """The check of `compare` and `suite` (`check_policy_spec`) reads the whole contract."""
    onnx_file = _copy(tmp_path)
    _edit_contract(onnx_file, lambda c: c.update(allocated="false"))
    with pytest.raises(ValueError) as error:
        check_policy_spec(f"onnx:{onnx_file}")
    _one_line(error, f"policy 'onnx:{onnx_file}'", "'allocated' is 'false'")
