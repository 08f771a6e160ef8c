"""The settings every crawl of the package shares, defined once.

The CLI's wave gait (:class:`pneumaquad.locomotion.walking.WalkSettings`) and the operator
console's online crawl (:class:`.online.OnlineCrawlSettings`) both extend
:class:`CrawlSettings`, so a foot lift or a static margin has one default wherever the
robot crawls.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CrawlSettings"]


@dataclass(frozen=True)
class CrawlSettings:
    """Settings of a statically stable crawl that do not depend on how it is planned.

    Attributes
    ----------
    step_height : float [m]
        Foot lift at mid-swing.
    minimum_margin : float [m]
        Static stability margin the body's sway or shift must plan before a leg lifts
        (distance of the centre of mass inside the support of the feet that stay down).
        60 mm is the margin with which the wave gait walked every terrain in our
        measurements (docs/robot.md).
    """

    step_height: float = 0.04
    minimum_margin: float = 0.06
