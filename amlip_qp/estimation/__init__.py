"""Base-state estimation from the robot's own sensors (IMU, encoders, foot contact)."""
