"""Scenarios: the named walks of the robots' profiles, speed profiles, and the closed loop built from a scenario."""
