"""Statically stable crawl gait planning for the quadruped (issue #6).

* :mod:`.stability` — support polygon and static stability margin.
* :mod:`.crawl` — the lateral-sequence wave gait with body sway (pure functions of time).
* :mod:`.walk` — the gait turned into joint-angle reference tables for the robot.
"""
