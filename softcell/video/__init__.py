"""Video: the camera's calibration, the paper's tracker (frame in, geometry out), tracking a film,
and the movies softcell draws (a synthetic top view to track, and animations to watch)."""
