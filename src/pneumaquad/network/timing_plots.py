"""Figures of a packet log: round-trip histogram and a gap / pause timeline.

The timeline serves the purpose of the thesis's Fig. 37 (Daepp 2011, ch. 5.3.2): show
when the exchange paused, for how long, and what was lost or malformed around it, so
that a pause in a trajectory plot can be matched to the network.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np

from pneumaquad.network.packet_log import MALFORMED_MIN, RECEIVED, SENT, PacketLog
from pneumaquad.network.timing import find_pauses, round_trip_times

DPI = 150
SECONDS_TO_MS = 1e3


def _save(fig: plt.Figure, path: Path | str) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_rtt_histogram(log: PacketLog, path: Path | str, deadline: float | None = None,
                       title: str = "") -> Path:
    """Histogram of the round-trip times of a log, in milliseconds.

    Parameters
    ----------
    log
        Packet log of the peer that sent pings / commands.
    path
        Output PNG (parent folders are created).
    deadline
        Optional deadline [s], drawn as a vertical line.
    title
        Figure title.

    Returns
    -------
    Path
        The written PNG.
    """
    rtts = round_trip_times(log) * SECONDS_TO_MS
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    if rtts.size:
        ax.hist(rtts, bins=min(100, max(10, rtts.size // 20)), color="tab:blue", alpha=0.8)
        for quantile, style in ((50, "-"), (99, "--")):
            value = float(np.percentile(rtts, quantile))
            ax.axvline(value, color="k", ls=style, lw=1, label=f"p{quantile} {value:.3f} ms")
    else:
        ax.text(0.5, 0.5, "no round trips in the log", ha="center", transform=ax.transAxes)
    if deadline is not None:
        ax.axvline(deadline * SECONDS_TO_MS, color="tab:red", lw=1.5, label="deadline")
    ax.set_xlabel("Round-trip time (ms)")
    ax.set_ylabel("Round trips")
    ax.grid(True, alpha=0.35)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize="small")
    if title:
        fig.suptitle(title)
    return _save(fig, path)


def plot_packet_timeline(log: PacketLog, nominal_period: float, path: Path | str,
                         pause_factor: float = 10.0, title: str = "") -> Path:
    """Inter-arrival gaps over time with pauses shaded and malformed packets marked.

    Parameters
    ----------
    log
        Packet log.
    nominal_period
        Nominal exchange period [s], drawn as a reference line.
    path
        Output PNG (parent folders are created).
    pause_factor
        Gaps longer than ``pause_factor * nominal_period`` are shaded as pauses.
    title
        Figure title.

    Returns
    -------
    Path
        The written PNG.
    """
    received = log.direction == RECEIVED
    valid = received & (log.classification < MALFORMED_MIN)
    # time since the first packet either way, not the raw monotonic clock
    stamps_all = np.concatenate([log.receive_time[received], log.send_time[~received]])
    stamps_all = stamps_all[np.isfinite(stamps_all)]
    origin = float(stamps_all.min()) if stamps_all.size else 0.0
    fig, ax = plt.subplots(figsize=(9, 4), layout="constrained")
    for mask, times, label, color in (
        (valid, log.receive_time, "received", "tab:blue"),
        (log.direction == SENT, log.send_time, "sent", "tab:orange"),
    ):
        stamps = np.sort(times[mask]) - origin
        if stamps.size > 1:
            ax.semilogy(stamps[1:], np.diff(stamps) * SECONDS_TO_MS, ".", ms=2, color=color,
                        label=f"{label} gap")
    arrivals = log.receive_time[valid]
    pauses = find_pauses(arrivals, pause_factor * nominal_period)
    for index, (start, duration) in enumerate(pauses):
        ax.axvspan(start - origin, start - origin + duration, color="tab:red", alpha=0.2,
                   label="pause" if index == 0 else None)
    malformed = log.receive_time[received & (log.classification >= MALFORMED_MIN)] - origin
    if malformed.size:
        ax.plot(malformed, np.full(malformed.size, nominal_period * SECONDS_TO_MS), "x",
                color="k", label="malformed")
    ax.axhline(nominal_period * SECONDS_TO_MS, color="0.4", lw=1, ls="--", label="nominal period")
    ax.set_xlabel("Time since the first packet (s)")
    ax.set_ylabel("Gap to previous packet (ms)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right", fontsize="small")
    if title:
        fig.suptitle(title)
    return _save(fig, path)
