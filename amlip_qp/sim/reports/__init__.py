"""Reports of a run: the JSON summary, the figures, the video, the choice of OpenGL for rendering."""
