"""The MuJoCo side of the closed loop, one job per subpackage, each importing only those above it in this list.

- :mod:`~amlip_qp.sim.world`: the plant (any MJCF model mapped to the
  controller's by name), its files, start pose, model mismatch, terrain, the
  IMU site and contact sensors added to it, its generated-C state read and
  control write;
- :mod:`~amlip_qp.sim.sensing`: what the controller is given from the plant
  (the ``ideal`` and ``robot`` sensor models);
- :mod:`~amlip_qp.sim.loop`: the closed loop (the harness, its log, the run's
  plain data, pushes, the controller on a user's own MuJoCo model, live runs);
- :mod:`~amlip_qp.sim.scenarios`: the named scenarios, their tables and speed
  profiles, and the closed loop built from one;
- :mod:`~amlip_qp.sim.reports`: the JSON summary, figures and video of a run.

The experiments (:mod:`amlip_qp.experiments`) and the command line sit above
and are never imported from here.
"""
