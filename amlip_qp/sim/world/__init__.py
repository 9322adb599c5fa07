"""The world: the MuJoCo plant, its files, start pose, model mismatch and terrain, the sensors' hardware on it.

Nothing here knows the controller's loop: :mod:`~amlip_qp.sim.sensing` reads
the plant, :mod:`~amlip_qp.sim.loop` steps it.
"""
