"""The quadruped robot: model, kinematics, coupled simulation."""
