"""What ``pneumaquad robot walk`` prints of its judgement: one verdict line for a walk, a
turn in place or a waypoint path (and a line per waypoint)."""

from __future__ import annotations

from typing import Any

from pneumaquad.cli.common import console
from pneumaquad.locomotion.walk_settings import WalkSettings

__all__ = ["print_walk_outcome"]


def print_walk_outcome(outcome: dict[str, Any] | None, settings: WalkSettings,
                       waypoints: bool = False) -> None:
    """Print the verdict of a judged walk (:func:`pneumaquad.locomotion.walk_run.run_walk`
    or ``run_waypoints`` with ``waypoints``): success or failure with the reasons and the
    figures it was judged on; None: the run stopped before the walk began."""
    if outcome is None:
        console.print("walking: not judged (the run stopped before the walk began)")
        return
    verdict = "success" if outcome["success"] else "failure"
    if waypoints:
        console.print(f"waypoints: [bold]{verdict}[/bold] ({', '.join(outcome['reasons'])})")
        for number, leg in enumerate(outcome.get("legs", []), start=1):
            target, reached = leg["waypoint [m]"], leg["reached [m]"]
            console.print(f"  waypoint {number} ({target[0]:g}, {target[1]:g}) m: reached "
                          f"({reached[0]:.3f}, {reached[1]:.3f}) m, error "
                          f"{leg['waypoint error [m]']:.3f} m; walk "
                          f"{'success' if leg['success'] else 'failure'} "
                          f"({', '.join(leg['reasons'])})", highlight=False)
        return
    if outcome.get("period [s]", settings.period) != settings.period:
        console.print(f"the gait cycle was shortened from {settings.period:g} s to "
                      f"{outcome['period [s]']:g} s (the same speed, a shorter stride): the "
                      "legs could not reach the plan of the cycle asked", highlight=False)
    if "distance travelled [m]" not in outcome:  # it did not begin: no verified stance
        console.print(f"walking: [bold]{verdict}[/bold] ({', '.join(outcome['reasons'])})")
        return
    if "turned [deg]" in outcome:
        console.print(f"turning: [bold]{verdict}[/bold] ({', '.join(outcome['reasons'])}); "
                      f"turned {outcome['turned [deg]']:.1f}° of "
                      f"{outcome['turn asked [deg]']:g}° (error "
                      f"{outcome['turn error [deg]']:+.1f}°), "
                      f"drifted {outcome['drift [m]']:.3f} m; stance feet slid "
                      f"{outcome['largest stance-foot slide [m]']:.2f} m")
        return
    console.print(f"walking: [bold]{verdict}[/bold] ({', '.join(outcome['reasons'])}); "
                  f"travelled {outcome['distance travelled [m]']:.3f} m of "
                  f"{settings.distance:g} m, "
                  f"air {outcome['air per metre [NL/m]']:.3g} NL/m; negative static margin "
                  f"{outcome['time with negative static margin [%]']:.0f} % of the time "
                  f"(loaded feet), tip-over margin "
                  f"{outcome['time with negative tip-over margin [%]']:.1f} % (median "
                  f"{outcome['median tip-over margin [m]'] * 1000:.0f} mm); stance feet slid "
                  f"{outcome['largest stance-foot slide [m]']:.2f} m")
