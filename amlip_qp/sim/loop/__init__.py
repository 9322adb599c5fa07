"""The closed loop: the harness, its per-tick log, the run's plain data, pushes, the loop on a user's own model.

Also the live runs of ``view`` (the keys' command, real-time ticks, without a window).
"""
