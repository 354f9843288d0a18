"""An agent as ONNX operators: normalisation, network, action head, stages and the residual
composition, each the graph form of the numpy code that runs the agent in Python.

The numpy forms are the reference (`controllers.agent.AgentPolicy.normalize`, SB3's
deterministic `predict`, `controllers.envelope_guard.guard_commands`,
`controllers.actuator_allocation.Allocation.allocate`, `controllers.allocation.allocate`,
`controllers.residual.residual_action`); each function here names the one it mirrors, and
tests/test_onnx_export.py holds the two to 1e-5 on random inputs and on the test suite's
observations. The arithmetic keeps the reference's precision: observations and stages in float64,
the network in float32, so the two differ only by the order of float32 sums in a matrix product.

Columns are kept as (n, 1) tensors throughout, so that every operation broadcasts like numpy's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "OPSET",
    "Graph",
    "action_head",
    "allocation_graph",
    "guard_graph",
    "network_graph",
    "normalisation_graph",
    "residual_graph",
]

# ONNX operator set 17 (2022): every operator used here, and runtimes from onnxruntime 1.12 on.
OPSET = 17


class Graph:
    """A growing ONNX graph: constants become initializers, each `op` one node with one output."""

    def __init__(self) -> None:
        self.nodes: list[Any] = []
        self.initializers: list[Any] = []
        self._count = 0

    def _name(self, stem: str) -> str:
        self._count += 1
        return f"{stem}_{self._count}"

    def const(self, value: Any, dtype: Any = np.float64) -> str:
        """An initializer holding ``value`` as an array of ``dtype``; its name."""
        from onnx import numpy_helper

        name = self._name("const")
        array = np.asarray(value, dtype=dtype)
        self.initializers.append(numpy_helper.from_array(array, name))
        return name

    def op(self, op_type: str, *inputs: str, output: str | None = None, **attrs: Any) -> str:
        """One node ``op_type`` of ``inputs``; the name of its output (``output`` if given)."""
        from onnx import helper

        out = output or self._name(op_type.lower())
        self.nodes.append(helper.make_node(op_type, list(inputs), [out], **attrs))
        return out

    def cast(self, x: str, dtype: Any) -> str:
        from onnx import helper

        return self.op("Cast", x, to=helper.np_dtype_to_tensor_dtype(np.dtype(dtype)))

    def column(self, x: str, index: int) -> str:
        """Column ``index`` of a matrix (n, d) as (n, 1)."""
        return self.op("Gather", x, self.const([index], np.int64), axis=1)

    def columns(self, *xs: str) -> str:
        """Columns (n, 1) side by side, (n, k)."""
        return self.op("Concat", *xs, axis=1)

    def clip(self, x: str, low: str, high: str) -> str:
        """numpy's clip: min(max(x, low), high), with tensors as bounds."""
        return self.op("Min", self.op("Max", x, low), high)

    def clip_const(self, x: str, low: float, high: float, dtype: Any = np.float64) -> str:
        return self.clip(x, self.const(low, dtype), self.const(high, dtype))


def normalisation_graph(
    g: Graph, observation: str, mean: np.ndarray, var: np.ndarray, clip: float, epsilon: float
) -> str:
    """VecNormalize's clip((o − μ)/√(σ² + ε), −c, c) in float64, as float32 for the network
    (`controllers.agent.AgentPolicy.normalize`)."""
    x = g.cast(observation, np.float64)
    scale = np.sqrt(np.asarray(var, np.float64) + epsilon)
    x = g.op("Div", g.op("Sub", x, g.const(mean)), g.const(scale))
    return g.cast(g.clip_const(x, -clip, clip), np.float32)


def network_graph(g: Graph, x: str, layers: Sequence[tuple[str, Any]]) -> str:
    """A torch MLP as ONNX: ``layers`` are ("linear", (W, b)), ("tanh", None), ("relu", None)
    or ("hardtanh", (low, high)) in order (`controllers.onnx_export.mlp_layers`), float32."""
    for kind, params in layers:
        if kind == "linear":
            weight, bias = params
            x = g.op("Gemm", x, g.const(weight, np.float32), g.const(bias, np.float32), transB=1)
        elif kind == "tanh":
            x = g.op("Tanh", x)
        elif kind == "relu":
            x = g.op("Relu", x)
        elif kind == "hardtanh":
            x = g.clip_const(x, params[0], params[1], np.float32)
        else:
            raise ValueError(f"network layer {kind!r} has no ONNX form here")
    return x


def action_head(g: Graph, x: str, low: np.ndarray, high: np.ndarray, squash: bool) -> str:
    """SB3's deterministic action from the network's mean: clipped to the action box, or, for a
    squashed (SAC) policy, tanh then `unscale_action`: low + ½(a + 1)(high − low); float32."""
    low32, high32 = np.asarray(low, np.float32), np.asarray(high, np.float32)
    if not squash:
        return g.clip(x, g.const(low32, np.float32), g.const(high32, np.float32))
    a = g.op("Tanh", x)
    half = g.op("Mul", g.const(0.5, np.float32), g.op("Add", a, g.const(1.0, np.float32)))
    return g.op(
        "Add", g.const(low32, np.float32), g.op("Mul", half, g.const(high32 - low32, np.float32))
    )


def _ramp(g: Graph, x: str, soft: float, hard: float) -> str:
    """1 − 2·clip((x − soft)/(hard − soft), 0, 1) (`controllers.envelope_guard._authority`)."""
    r = g.op("Div", g.op("Sub", x, g.const(soft)), g.const(hard - soft))
    return g.op("Sub", g.const(1.0), g.op("Mul", g.const(2.0), g.clip_const(r, 0.0, 1.0)))


def guard_graph(g: Graph, commands: str, observation: str, index: Sequence[int], guard: Any) -> str:
    """The envelope guard (`controllers.envelope_guard.guard_commands`): a_M clipped to the pitch
    ramps of θ + T·q, a_X floored by the low-speed ramp (when on) and capped by the surge ramp of
    u; float32 commands in and out."""
    obs = g.cast(observation, np.float64)
    theta, q, u = (g.column(obs, i) for i in index)
    predicted = g.op("Add", theta, g.op("Mul", g.const(guard.lookahead_s), q))
    soft, hard = math.radians(guard.pitch_soft_deg), math.radians(guard.pitch_hard_deg)
    nose_up = _ramp(g, predicted, soft, hard)
    nose_down = _ramp(g, g.op("Neg", predicted), soft, hard)
    a = g.cast(commands, np.float64)
    a_x = g.column(a, 0)
    if guard.has_floor:
        floor = _ramp(g, g.op("Neg", u), -guard.surge_floor_soft, -guard.surge_floor_hard)
        a_x = g.op("Max", a_x, g.op("Neg", floor))
    a_x = g.op("Min", a_x, _ramp(g, u, guard.surge_soft, guard.surge_hard))
    if guard.nose_up_command > 0.0:
        a_m = g.clip(g.column(a, 1), g.op("Neg", nose_down), nose_up)
    else:  # the stern plane: a positive command pitches the nose down
        a_m = g.clip(g.column(a, 1), g.op("Neg", nose_up), nose_down)
    return g.cast(g.columns(a_x, a_m, g.column(a, 2)), np.float32)


def _fin_angle(g: Graph, moment: str, gain: str, direction: float, limit: float) -> str:
    """moment/gain clipped to ±limit; full deflection towards the moment where gain = 0
    (`controllers.allocation.fin_angle`)."""
    no_flow = g.op("Equal", gain, g.const(0.0))
    safe = g.op("Where", no_flow, g.const(1.0), gain)
    towards = g.op("Mul", g.const(direction * limit), g.op("Sign", moment))
    angle = g.op("Where", no_flow, towards, g.op("Div", moment, safe))
    return g.clip_const(angle, -limit, limit)


def _propeller_and_fins(g: Graph, tau: Sequence[str], velocity: Sequence[str], p: Any) -> str:
    """Normalised (shaft speed, stern plane, rudder) for τ_d at (u, v, w)
    (`controllers.allocation.allocate`, docs/model.md §2.7); columns (n, 1), float64."""
    x_d, m_d, n_d = tau
    u, v, w = velocity
    uu, vv, ww = (g.op("Mul", c, c) for c in (u, v, w))
    half_rho = g.const(0.5 * p.water_density)
    k_s = g.op(
        "Mul",
        g.op("Mul", g.op("Mul", half_rho, g.op("Add", uu, ww)), g.const(p.fin_area_stern)),
        g.const(p.lift_coeff_stern),
    )
    k_r = g.op(
        "Mul",
        g.op("Mul", g.op("Mul", half_rho, g.op("Add", uu, vv)), g.const(p.fin_area_rudder)),
        g.const(p.lift_coeff_rudder),
    )
    stern_gain = g.op("Mul", g.const(p.x_stern), k_s)
    rudder_gain = g.op("Mul", g.const(-p.x_rudder), k_r)
    delta_s = _fin_angle(g, m_d, stern_gain, float(np.sign(p.x_stern)), p.delta_max_stern)
    delta_r = _fin_angle(g, n_d, rudder_gain, float(-np.sign(p.x_rudder)), p.delta_max_rudder)
    if p.fin_induced_drag != 1.0:  # κ (docs/model.md §2.6); the graphs of κ = 1 stay as they were
        k_s, k_r = (g.op("Mul", g.const(p.fin_induced_drag), k) for k in (k_s, k_r))
    drag_r = g.op("Mul", g.op("Mul", g.op("Neg", k_r), delta_r), delta_r)
    fin_drag = g.op("Sub", drag_r, g.op("Mul", g.op("Mul", k_s, delta_s), delta_s))
    thrust = g.op("Div", g.op("Sub", x_d, fin_drag), g.const(1.0 - p.thrust_deduction))
    d = p.prop_diameter
    t_coeff = g.op("Div", thrust, g.const(p.water_density * d**4))  # [rps²]
    speed = g.op("Sqrt", g.op("Add", g.op("Add", uu, vv), ww))
    v_a = g.op("Mul", g.const(p.advance_speed_ratio), speed)
    b = g.op("Mul", g.const((p.kt_max - p.kt_0) / p.advance_max), g.op("Div", v_a, g.const(d)))
    zero = g.const(0.0)
    root = g.op(
        "Add", g.op("Mul", b, b), g.op("Mul", g.const(4.0 * p.kt_0), t_coeff)
    )  # b² + 4·K_T0·T
    ahead = g.op(
        "Div",
        g.op("Add", g.op("Neg", b), g.op("Sqrt", g.op("Max", root, zero))),
        g.const(2.0 * p.kt_0),
    )
    astern = g.op(
        "Neg", g.op("Sqrt", g.op("Div", g.op("Max", g.op("Neg", t_coeff), zero), g.const(p.kt_0)))
    )
    forward = g.op("GreaterOrEqual", t_coeff, zero)
    rpm = g.op("Mul", g.const(60.0), g.op("Where", forward, ahead, astern))
    commands = g.columns(
        g.op("Div", rpm, g.const(p.rpm_max)),
        g.op("Div", delta_s, g.const(p.delta_max_stern)),
        g.op("Div", delta_r, g.const(p.delta_max_rudder)),
    )
    return g.clip_const(commands, -1.0, 1.0)


def allocation_graph(g: Graph, commands: str, observation: str, allocation: Any) -> tuple[str, str]:
    """The actuator allocation (`controllers.actuator_allocation.Allocation.allocate`): (the
    actuator's commands, the delivered command in the agent's units), both float32 (n, 3)."""
    a = g.clip_const(g.cast(commands, np.float64), -1.0, 1.0)
    obs = g.cast(observation, np.float64)
    u, v, w = (g.column(obs, int(i)) for i in allocation.velocity_index)
    speed_squared = g.op("Max", g.op("Mul", u, g.op("Abs", u)), g.const(0.0))
    authority = g.op("Mul", g.const(allocation.fin_gain), speed_squared)  # [N·m]
    x_max, m_max, n_max = (float(limit) for limit in allocation.limits)
    a_x = g.column(a, 0)
    m_d = g.op("Mul", g.column(a, 1), g.const(m_max))
    n_d = g.op("Mul", g.column(a, 2), g.const(n_max))
    low = g.op("Neg", authority)
    m_delivered, n_delivered = (g.clip(m, low, authority) for m in (m_d, n_d))
    previous = g.cast(
        g.columns(
            a_x, g.op("Div", m_delivered, g.const(m_max)), g.op("Div", n_delivered, g.const(n_max))
        ),
        np.float32,
    )
    if allocation.actuator == "fins":
        out = g.columns(
            a_x, _fin_angle(g, m_d, authority, 1.0, 1.0), _fin_angle(g, n_d, authority, 1.0, 1.0)
        )
    else:
        tau = (g.op("Mul", a_x, g.const(x_max)), m_delivered, n_delivered)
        out = _propeller_and_fins(g, tau, (u, v, w), allocation.actuator_params)
    return g.cast(out, np.float32), previous


def _fin_margin_factor(g: Graph, b: str, margin: float) -> str:
    """(n, 3) float64 [s, 1, 1] with s = clip((1 − max(|b_M|, |b_N|)) / m, 0, 1): the thrust
    reach's scale of `controllers.residual.reach_below`."""
    fins = g.op("Max", g.op("Abs", g.column(b, 1)), g.op("Abs", g.column(b, 2)))
    room = g.op("Div", g.op("Sub", g.const(1.0, np.float64), fins), g.const(margin, np.float64))
    scale = g.clip_const(room, 0.0, 1.0)
    ones = g.op("Expand", g.const([[1.0, 1.0]], np.float64), g.op("Shape", scale))  # (n, 2)
    return g.columns(scale, ones)


def residual_graph(
    g: Graph,
    base_action: str,
    correction: str,
    previous: str,
    started: str,
    bound: Sequence[float],
    filter_max: float,
    bound_below: Sequence[float] | None = None,
    brake_fin_margin: float | None = None,
) -> str:
    """The applied action of a residual agent (`controllers.residual.residual_action`):
    clip(b + β ⊙ clip(c, −1, 1), −1, 1) (β⁻ ``bound_below`` in place of β where c < 0, its thrust
    entry scaled by the base's fin margin with ``brake_fin_margin``), then
    with α_max > 0 the learned low-pass α ⊙ a_prev + (1 − α) ⊙ a with α = α_max·clip(g, 0, 1),
    0 where not ``started``; float32."""
    b = g.cast(base_action, np.float64)
    c = g.cast(correction, np.float64)
    c_first = g.op(
        "Slice",
        c,
        g.const([0], np.int64),
        g.const([3], np.int64),
        g.const([1], np.int64),
    )
    reach = g.clip_const(c_first, -1.0, 1.0)
    above = g.const(np.asarray(bound, np.float64))
    if bound_below is None and brake_fin_margin is None:
        step = g.op("Mul", above, reach)
    else:
        below = g.const(np.asarray(bound if bound_below is None else bound_below, np.float64))
        if brake_fin_margin is not None:
            below = g.op("Mul", below, _fin_margin_factor(g, b, brake_fin_margin))
        negative = g.op("Less", reach, g.const(0.0, np.float64))
        step = g.op("Mul", g.op("Where", negative, below, above), reach)
    target = g.cast(g.clip_const(g.op("Add", b, step), -1.0, 1.0), np.float32)
    if filter_max == 0.0:
        return target
    gate = g.op("Slice", c, g.const([3], np.int64), g.const([6], np.int64), g.const([1], np.int64))
    gate = g.cast(g.clip_const(gate, 0.0, 1.0), np.float32)
    alpha = g.op("Mul", g.op("Mul", g.const(filter_max, np.float32), gate), started)
    kept = g.op("Mul", alpha, previous)
    fresh = g.op("Mul", g.op("Sub", g.const(1.0, np.float32), alpha), target)
    return g.op("Add", kept, fresh)
