"""Figures of `benchmarks.analysis.stats` results: interval plots, probability of improvement,
performance profiles, learning curves with CI bands; atomic saving.

Only matplotlib's object-oriented API (`matplotlib.figure.Figure` with the Agg canvas) is used:
no pyplot state, no backend switching, so these are safe in workers and tests.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from auv_gym.support.files import temporary_prefix
from benchmarks.analysis.stats import AGGREGATE
from benchmarks.reports.plotting import policy_colours


def policy_colors(policies) -> dict[str, Any]:
    """One colour per policy, the same in every figure
    (`benchmarks.reports.plotting.policy_colours`)."""
    return policy_colours(list(policies))


def _errorbars(ax, intervals: list, offset: float = 0.0, **style) -> None:
    """Horizontal Interval(value, low, high) bars, one row per entry, first row on top."""
    iv = np.array(intervals, dtype=float).reshape(-1, 3)
    rows = np.arange(len(iv)) + offset
    ax.errorbar(iv[:, 0], rows, xerr=np.abs(iv[:, 1:].T - iv[:, 0]), capsize=3, ls="", **style)


def _scale(ax, which: str, values) -> None:
    """Log scale when the values are positive and span > 3x; labels '0.02' at 1-2-5 steps
    within 1.5 decades, at decades beyond (sci-notation minor labels overlap in narrow panels)."""
    lo, hi = float(np.min(values)), float(np.max(values))
    if lo <= 0 or hi < 3 * lo:
        return
    getattr(ax, f"set_{which}scale")("log")
    axis = getattr(ax, f"{which}axis")
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0) if hi < 30 * lo else (1.0,)))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def _ci(summary: Mapping[str, Any]) -> str:
    return f"{100 * summary['confidence']:g} %"


def _panels(n: int, width_in: float, height_in: float, sharey: bool = False, columns: int = 3):
    """A grid of ``n`` panels, at most ``columns`` wide (rows below), unused cells hidden."""
    if n < 1:
        raise ValueError("nothing to plot: no panels")
    cols = min(n, columns)
    rows = -(-n // cols)
    fig = Figure(figsize=(width_in * cols, height_in * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False, sharey=sharey).ravel()
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, list(axes[:n])


def _label_policies(axes: list, policies: list[str]) -> None:
    """Policy names on the shared y axis; `Figure.subplots` shows them on the first column."""
    axes[0].set_yticks(range(len(policies)), policies)
    axes[0].invert_yaxis()  # first policy on top (the axis is shared: once)


def interval_figure(summary: Mapping[str, Any], unit: str = "m") -> Figure:
    """One panel per scope in a grid: IQM (dots) and mean (squares) with CIs per policy."""
    scopes, policies = summary["scopes"], summary["policies"]
    columns = 5
    fig, axes = _panels(len(scopes), 2.9, 0.22 * len(policies) + 1.0, sharey=True, columns=columns)
    for ax, scope in zip(axes, scopes, strict=True):
        for k, (name, label, dy) in enumerate((("iqm", "IQM", -0.15), ("mean", "mean", 0.15))):
            bars = [summary[name][scope][p] for p in policies]
            _errorbars(ax, bars, dy, marker="os"[k], color=("k", "0.55")[k], ms=3, label=label)
        _scale(ax, "x", [summary[m][scope][p][1:] for m in ("iqm", "mean") for p in policies])
        ax.set_title(scope, fontsize=9)
        ax.set_xlabel(f"RMS distance [{unit}]", fontsize=8)
        ax.grid(True, axis="x", which="both", alpha=0.3)
    _label_policies(axes, policies)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"IQM and mean with {_ci(summary)} confidence intervals (lower is better)")
    return fig


def improvement_figure(summary: Mapping[str, Any]) -> Figure:
    """One panel per scope in a grid: P(policy beats the reference on an episode) with CIs."""
    scopes = [s for s in summary["scopes"] if s in summary["improvement"]]
    if not scopes:
        reference = summary["reference"]
        raise ValueError(
            f"summary: no probability of improvement: {reference!r} not among the policies"
        )
    policies = list(summary["improvement"][scopes[0]])
    columns = 5
    fig, axes = _panels(len(scopes), 2.9, 0.22 * len(policies) + 1.0, sharey=True, columns=columns)
    for ax, scope in zip(axes, scopes, strict=True):
        _errorbars(
            ax, [summary["improvement"][scope][p] for p in policies], marker="o", ms=3, color="k"
        )
        ax.axvline(0.5, color="k", ls="--", lw=0.8)
        ax.set(xlim=(-0.02, 1.02))
        ax.set_title(scope, fontsize=9)
        ax.set_xlabel(f"P(better than {summary['reference']})", fontsize=8)
    _label_policies(axes, policies)
    fig.suptitle(
        f"Probability of a smaller RMS distance than {summary['reference']} on an episode "
        f"(ties ½), {_ci(summary)} confidence intervals"
    )
    return fig


def profile_figure(summary: Mapping[str, Any], scope: str = AGGREGATE, unit: str = "m") -> Figure:
    """Performance profiles of one scope: fraction of episodes below τ with CI bands; the legend
    beside the axes."""
    if scope not in summary["profiles"]:
        raise ValueError(f"scope={scope!r}: not among {list(summary['profiles'])}")
    fig = Figure(figsize=(6.0, 4.0), layout="constrained")
    ax = fig.subplots()
    colors = policy_colors(summary["profiles"][scope])
    for policy, prof in summary["profiles"][scope].items():
        ax.plot(prof["tau_m"], prof["fraction"], color=colors[policy], label=policy)
        ax.fill_between(prof["tau_m"], prof["low"], prof["high"], color=colors[policy], alpha=0.2)
    _scale(ax, "x", np.concatenate([p["tau_m"] for p in summary["profiles"][scope].values()]))
    title = f"{scope}: performance profiles, {_ci(summary)} bands"
    ax.set(
        xlabel=f"threshold τ: RMS distance [{unit}]",
        ylabel="fraction of episodes < τ",
        ylim=(-0.02, 1.02),
        title=title,
    )
    ax.grid(True, which="both", alpha=0.3)
    # Beside the axes: with twenty-odd policies a legend inside covers the curves it names.
    policies = len(summary["profiles"][scope])
    columns = 1 if policies <= 24 else 2
    fig.legend(loc="outside right upper", fontsize=7, ncols=columns)
    fig.set_figwidth(fig.get_figwidth() + 1.9 * columns)
    return fig


def learning_curve_figure(
    panels: Mapping[str, Mapping[str, Mapping[str, Any]]], ylabel: str = "IQM RMS distance [m]"
) -> Figure:
    """One panel per x label ({x label: {policy: `learning_curve` output}}), shared log y; one
    legend for all panels, below them, so that no curve hides behind it."""
    fig, axes = _panels(len(panels), 4.5, 3.6, sharey=True)
    labels: dict[str, Any] = {}
    for ax, (xlabel, curves) in zip(axes, panels.items(), strict=True):
        colours = policy_colours(list(curves))
        for policy, c in curves.items():
            colour = colours[policy]
            label = f"{policy} ({c['n_runs']} runs)"
            (labels[label],) = ax.plot(c["x"], c["iqm"], color=colour, label=label)
            ax.fill_between(c["x"], c["low"], c["high"], color=colour, alpha=0.2)
        _scale(ax, "y", np.concatenate([np.r_[c["low"], c["high"]] for c in curves.values()]))
        ax.set(xlabel=xlabel, ylabel=ylabel)
        ax.grid(True, which="both", alpha=0.3)
    columns = max(1, min(len(labels), 3))
    fig.legend(
        list(labels.values()), list(labels), loc="outside lower center", ncols=columns, fontsize=7
    )
    if len(labels) > columns:  # room for the legend's rows below the panels
        fig.set_figheight(fig.get_figheight() + 0.18 * -(-len(labels) // columns))
    return fig


def tradeoff_figure(
    summary: Mapping[str, Any],
    chattering: Mapping[str, Mapping[str, Mapping[str, float]]],
    scopes: list[str],
    max_distance_m: float = 1.0,
) -> Figure:
    """Accuracy against smoothness, one panel per scope: mean RMS distance [m] over mean
    chattering [1/s], each with its CI, per policy; policies whose mean distance exceeds
    ``max_distance_m`` (or without a chattering value) are left out and named in the title."""
    fig, axes = _panels(len(scopes), 4.2, 3.4)
    colors = policy_colors(summary["policies"])
    for ax, scope in zip(axes, scopes, strict=True):
        shown, left_out, heights = [], [], []
        for policy, distance in summary["mean"][scope].items():
            chat = chattering.get(scope, {}).get(policy)
            if chat is None or not np.isfinite(chat["value"]) or distance.value > max_distance_m:
                left_out.append(policy)
                continue
            shown.append(policy)
            x = np.array([chat["value"], chat["low"], chat["high"]])
            y = np.array([distance.value, distance.low, distance.high])
            heights.extend(y)
            ax.errorbar(
                x[0],
                y[0],
                xerr=np.abs(x[1:, None] - x[0]),
                yerr=np.abs(y[1:, None] - y[0]),
                capsize=3,
                marker="o",
                ls="",
                label=policy,
                color=colors[policy],
            )
        if heights:
            _scale(ax, "y", heights)
        ax.set_xlabel("chattering [1/s]")
        ax.set_ylabel("mean RMS distance [m]")
        title = (
            scope
            if not left_out
            else f"{scope}\n(> {max_distance_m:g} m: {len(left_out)} left out)"
        )
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        if shown:
            ax.legend(fontsize=7)
    fig.suptitle(f"Accuracy against smoothness, {_ci(summary)} CIs")
    return fig


def save_figure(fig: Figure, path: str | os.PathLike, dpi: int = 150) -> Path:
    """Write ``fig`` atomically (temporary file in the same folder, then os.replace)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=temporary_prefix(path), suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, format=path.suffix.lstrip(".") or "png", dpi=dpi)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return path
