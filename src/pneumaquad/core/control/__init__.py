"""Controllers shared by the rig and the robot."""
