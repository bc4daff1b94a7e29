"""simrig: a test bench for multi-camera multi-object trackers on moving vehicles.

Data flows one way: a scenario (``scenarios``) drives highway-env traffic (``simrig.world``) that a
virtual camera rig (``simrig.rig``, ``simrig.geometry``) sees; the result is written as a dataset
(``simrig.dataset``). The shared records live in ``simrig.types``.
"""

__version__ = "0.1.0"
