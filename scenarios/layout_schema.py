"""Road layouts simrig builds from highway-env's road parts (``[traffic.layout]``), for runs of any length.

highway-env's own maps end after a few hundred metres (``merge-v0`` 460 m, ``two-way-v0`` 800 m, ``exit-v0``
1 km, ``intersection-v0`` about 100 m a branch), so an ego driving through one leaves the road within a minute. A
layout is a long road (``length_m``) whose feature repeats: an on-ramp, an exit, a crossing road, or oncoming
lanes all along. :mod:`simrig.world.layouts` builds each one; the keys here are those of each kind.

Every share is the fraction of new vehicles placed on that part of the road (the rest go on the ego's own
carriageway), so a share of 0 leaves the feature empty and 1 puts all traffic there.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from .base import Strict

Share = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
"""[-] a fraction of new vehicles."""
LayoutLength = Annotated[float, Field(ge=1000, le=20000, allow_inf_nan=False)]
"""[m] how long the road is: the ego starts near its beginning and must not reach its end in the frames asked
(at 25 m/s, 1,000 frames at 10 Hz cover 2.5 km)."""
Spacing = Annotated[float, Field(ge=300, le=5000, allow_inf_nan=False)]
"""[m] distance between two repeats of a layout's feature."""


class TwoWayLayout(Strict):
    """A road with oncoming traffic: ``lanes_per_direction`` lanes each way, the two directions side by side with no
    lane change between them (no overtaking on the oncoming side)."""

    kind: Literal["two_way"]
    lanes_per_direction: Annotated[int, Field(ge=1, le=3)] = 1
    """[-] lanes in each direction."""
    oncoming_share: Share = 0.5
    """[-] share of new vehicles placed on the oncoming lanes."""
    length_m: LayoutLength = 6000.0


class RampsLayout(Strict):
    """A motorway with an on-ramp every ``ramp_spacing_m`` on the right: a ramp runs beside the road, converges,
    and ends in a 200 m acceleration lane from which its vehicles must merge (highway-env's ``merge-v0`` section,
    repeated, with a longer acceleration lane). IDM/MOBIL vehicles merge only into a gap, so a ramp's vehicles
    merge when the motorway runs below its capacity; a ramp vehicle that comes to a stop at the end of its lane
    never changes lane (highway-env's MOBIL needs ≥ 1 m/s) and stays until it leaves the window."""

    kind: Literal["ramps"]
    lanes: Annotated[int, Field(ge=1, le=4)] = 2
    """[-] lanes of the motorway."""
    ramp_spacing_m: Spacing = 600.0
    ramp_share: Share = 0.3
    """[-] share of new vehicles placed on the ramps."""
    length_m: LayoutLength = 6000.0


class ExitsLayout(Strict):
    """A motorway with an exit every ``exit_spacing_m``: the rightmost lane forks into a ramp that curves away to the
    right. Vehicles that will leave are placed in the rightmost lane and take the next exit."""

    kind: Literal["exits"]
    lanes: Annotated[int, Field(ge=2, le=5)] = 3
    """[-] lanes of the motorway."""
    exit_spacing_m: Spacing = 500.0
    exit_share: Share = 0.3
    """[-] share of new vehicles that take the next exit (placed in the rightmost lane)."""
    length_m: LayoutLength = 6000.0


class CrossingsLayout(Strict):
    """A two-way road crossed every ``crossing_spacing_m`` by a two-way side road whose vehicles give way at a stop
    line: they wait while a main-road vehicle would reach the junction within 4 s
    (:class:`simrig.world.layouts.CrossingRoad`). The ego drives through every crossing; others arrive ahead,
    behind, oncoming and from both side branches."""

    kind: Literal["crossings"]
    crossing_spacing_m: Annotated[float, Field(ge=100, le=2000, allow_inf_nan=False)] = 200.0
    """[m] distance between two crossings."""
    side_share: Share = 0.4
    """[-] share of new vehicles placed on the side roads."""
    oncoming_share: Share = 0.3
    """[-] share of new vehicles placed on the oncoming lane of the main road."""
    side_speed_mps: Annotated[float, Field(gt=0, le=40, allow_inf_nan=False)] = 12.0
    """[m/s] speed limit of the side roads (a vehicle that has yielded drives off at its lane's limit)."""
    length_m: LayoutLength = 4000.0

    @model_validator(mode="after")
    def _check(self) -> CrossingsLayout:
        if self.side_share + self.oncoming_share > 1.0:
            raise ValueError(f"side_share + oncoming_share: {self.side_share:g} + {self.oncoming_share:g} exceeds 1")
        return self


Layout = Annotated[TwoWayLayout | RampsLayout | ExitsLayout | CrossingsLayout, Field(discriminator="kind")]
"""One road layout (module docstring)."""
LAYOUT_KINDS = ("two_way", "ramps", "exits", "crossings")
