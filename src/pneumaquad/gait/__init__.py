"""Statically stable crawl gait planning for the quadruped (issue #6).

* :mod:`.stability` — support polygon and static stability margin.
* :mod:`.crawl` — the lateral-sequence wave gait with body sway (pure functions of time).
* :mod:`.online` — the step-at-a-time crawl the operator console drives live.
* :mod:`.settings` — the settings both crawls share (:class:`.settings.CrawlSettings`).

The walk plan and the walking driver on the robot are in :mod:`pneumaquad.locomotion`.
"""
