"""Figures of the motion-control experiments in the style of paper 001 Figs. 11–13.

:func:`plot_step` draws one ``speed_step`` / ``roll_step`` result (the CLI's ``--plot``);
:func:`plot_fig11`, :func:`plot_fig12` and :func:`plot_fig13` draw every case of a
:func:`~lab.pendulum.figures.run_figures` result with both controllers, as docs/pendulum.md shows.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

COLOURS = {"lmpc": "tab:blue", "rslqr": "tab:blue", "pid": "tab:red"}
LABELS = {"lmpc": "LMPC", "rslqr": "RSLQR", "pid": "PID"}


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _col(result: dict[str, Any], key: str) -> np.ndarray:
    return np.array([row[key] for row in result["series"]], dtype=float)


def _fmt(x: float | None, unit: str = " s", digits: int = 2) -> str:
    return "—" if x is None else f"{x:.{digits}f}{unit}"


def _speed_title(res: dict[str, Any]) -> str:
    return f"{res['speed_m_s']} m/s on a {res['floor']} floor"


def _roll_title(res: dict[str, Any]) -> str:
    return f"{res['speed_m_s']} m/s, desired roll {res['roll_rad']} rad"


def _legend_text(res: dict[str, Any]) -> str:
    return (
        f"{LABELS[res['controller']]}: rise {_fmt(res['rise_time_s'], digits=3)}, "
        f"overshoot {100 * res['overshoot']:.1f} %, settle {_fmt(res['settling_time_s'])}"
    )


def plot_step(result: dict[str, Any], out: str | Path) -> None:
    """One speed or roll step: the controlled variable with its reference, the pendulum angle, the torque."""
    plt = _plt()
    t = _col(result, "t")
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True, layout="constrained")
    ctrl = result["controller"]
    colour = COLOURS[ctrl]
    if result["experiment"] == "speed_step":
        axes[0].plot(t, _col(result, "v_ref"), "k--", lw=1, label="desired speed")
        axes[0].plot(t, _col(result, "v"), color=colour, label=_legend_text(result))
        axes[0].set_ylabel("speed (m/s)")
        axes[1].plot(t, np.degrees(_col(result, "pitch")), color=colour)
        axes[1].set_ylabel("pendulum pitch α (°)")
        title = f"{result['robot']} · speed step · {_speed_title(result)}"
    else:
        axes[0].plot(t, _col(result, "roll_ref"), "k--", lw=1, label="desired roll")
        axes[0].plot(t, _col(result, "roll"), color=colour, label=_legend_text(result))
        axes[0].set_ylabel("robot roll φ (rad)")
        axes[1].plot(t, np.degrees(_col(result, "pendulum_roll")), color=colour)
        axes[1].set_ylabel("pendulum roll β (°)")
        title = f"{result['robot']} · roll step · {_roll_title(result)}"
    axes[2].plot(t, _col(result, "torque"), color=colour)
    axes[2].set_ylabel("motor torque (N m)")
    axes[2].set_xlabel("t (s)")
    axes[0].legend(fontsize=8, loc="lower right")
    axes[0].set_title(title, fontsize=10)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def _panel_grid(n: int) -> tuple[int, int]:
    return (2, 2) if n == 4 else (1, n)


def _compare(figs: dict[str, Any], group: str, key: str, ylabel: str, title: str, out: str | Path,
             scale: float = 1.0, ref_key: str | None = None, limit: float | None = None) -> None:
    plt = _plt()
    cases = figs[group]
    rows, cols = _panel_grid(len(cases))
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.8 * rows), layout="constrained", squeeze=False)
    for i, case in enumerate(cases):
        ax = axes.flat[i]
        first = next(iter(case.values()))
        t = _col(first, "t")
        if ref_key is not None:
            ax.plot(t, _col(first, ref_key) * scale, "k--", lw=1, label="desired")
        for name, res in case.items():
            label = _legend_text(res) if ref_key is not None else LABELS[name]
            ax.plot(_col(res, "t"), _col(res, key) * scale, color=COLOURS[name], lw=1.3, label=label)
        if limit is not None:
            for sign in (1, -1):
                ax.axhline(sign * limit, color="0.5", ls=":", lw=1)
        sub = _speed_title(first) if group == "fig11" else _roll_title(first)
        ax.set_title(f"({chr(97 + i)}) {sub}", fontsize=9)
        ax.set_xlabel("t (s)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    fig.suptitle(title, fontsize=11)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_fig11(figs: dict[str, Any], out: str | Path) -> None:
    """Fig. 11: speed from rest to 0.5 and 1.5 m/s on tiled and rubber floors, LMPC vs PID."""
    _compare(figs, "fig11", "v", "speed (m/s)", f"{figs['robot']} · Fig. 11: curves of velocity change",
             out, ref_key="v_ref")


def plot_fig12(figs: dict[str, Any], out: str | Path) -> None:
    """Fig. 12: the pendulum pitch during the Fig. 11 runs (dotted: the 15° bound of paper 001 §5.1)."""
    _compare(figs, "fig12" if "fig12" in figs else "fig11", "pitch", "pendulum pitch α (°)",
             f"{figs['robot']} · Fig. 12: curves of pitch change", out, scale=180.0 / math.pi, limit=15.0)


def plot_fig13(figs: dict[str, Any], out: str | Path) -> None:
    """Fig. 13: roll steps while rolling, RSLQR vs PID."""
    _compare(figs, "fig13", "roll", "robot roll φ (rad)", f"{figs['robot']} · Fig. 13: curves of roll angle change",
             out, ref_key="roll_ref")


__all__ = ["plot_fig11", "plot_fig12", "plot_fig13", "plot_step"]
