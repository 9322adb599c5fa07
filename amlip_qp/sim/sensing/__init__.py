"""Sensing: the controller's measurement from the plant, the ``ideal`` and ``robot`` sensor models."""
