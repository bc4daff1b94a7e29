"""What each camera can see: vehicle shapes, analytic silhouettes, pyrender segmentation and colour renders.

``shapes`` and ``silhouette`` are numpy only; ``scene`` (and ``visibility``) import pyrender, which is set
up for headless EGL rendering on import.
"""
