"""Locomotion: walking the simulated robot.

Above :mod:`pneumaquad.robot` (the coupled simulation) and :mod:`pneumaquad.gait` (pure
planning geometry): the walk plan on the robot's kinematics (:mod:`.walk`), the walking
driver and its judgement (:mod:`.walking`), and the per-chunk corrections it runs: the
force-controlled stance (:mod:`.stance_control`), the swing height from the ground
(:mod:`.swing_control`) and the heading hold (:mod:`.heading_control`).
"""
