"""A tracker that misbehaves on frame 2 in the way ``mode`` says, for the bad-input tests
(``--tracker misbehaving_trackers:Misbehaving --param mode=...``)."""

from simrig.types import ActorClass, Box3D, Track


def _track(track_id=1, label=ActorClass.CAR, score=0.9, box3d=None, boxes2d=None):
    box = Box3D(10.0, 0.0, 0.8, 4.5, 1.9, 1.6, 0.0, 0.0, 0.0) if box3d is None else box3d
    return Track(track_id=track_id, label=label, score=score, box3d=box, boxes2d=boxes2d or {})


BAD = {
    "dict": lambda: {"id": 1},
    "none": lambda: None,
    "string_ids": lambda: [_track(track_id="a")],
    "float_ids": lambda: [_track(track_id=1.7)],
    "bool_ids": lambda: [_track(track_id=True)],
    "duplicate_ids": lambda: [_track(1), _track(1)],
    "unknown_label": lambda: [_track(label="plane")],
    "nan_score": lambda: [_track(score=float("nan"))],
    "nan_box": lambda: [_track(box3d=Box3D(float("nan"), 0.0, 0.8, 4.5, 1.9, 1.6, 0.0, 0.0, 0.0))],
    "unknown_camera": lambda: [_track(boxes2d={"NOWHERE": None})],
    "not_tracks": lambda: ["a track"],
    "score_above_1": lambda: [_track(score=1.5)],
    "negative_id": lambda: [_track(track_id=-3)],
    "huge_id": lambda: [_track(track_id=2**64)],
    "million": lambda: [_track()] * 1_000_000,
}


class Misbehaving:
    def __init__(self, mode: str = "raise"):
        self.mode = mode

    def reset(self, *, rig, seed=None):
        self.frame = 0

    def step(self, frame):
        self.frame += 1
        if self.frame < 3:
            return [_track()]
        if self.mode == "raise":
            raise ZeroDivisionError("division by zero in the user's tracker")
        if self.mode == "exit":
            raise SystemExit(3)
        return BAD[self.mode]()


class FailsWhenBuilt:
    """A tracker whose constructor raises (a missing model file, say)."""

    def __init__(self):
        raise FileNotFoundError("weights.pt")

    def reset(self, *, rig, seed=None):
        pass

    def step(self, frame):
        return []
