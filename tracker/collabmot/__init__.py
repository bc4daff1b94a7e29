"""CollabMOT (Ninh and Kim, IEEE Access 2024): stereo collaborative 2D tracking on top of two single-camera trackers."""

from .tracker import SINGLE_CAMERA_TRACKERS, CollabMOT, SemiOnlineCollabMOT, collabmot

__all__ = ["SINGLE_CAMERA_TRACKERS", "CollabMOT", "SemiOnlineCollabMOT", "collabmot"]
