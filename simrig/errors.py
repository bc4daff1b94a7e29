"""simrig's exceptions: each carries a one-line message that names what is wrong and where."""


class SimrigError(Exception):
    """Base class of every error simrig reports to a user (the CLI prints the message alone)."""


class OptionError(SimrigError):
    """An option's value, or a combination of options, is not valid; the message starts with the option
    (``--samples: ...``). The command line adds where its options are described."""


class DatasetError(SimrigError):
    """A dataset folder is missing, incomplete, corrupt, or would be overwritten."""


class DatasetExistsError(DatasetError):
    """The output folder already holds a complete dataset and overwriting was not asked for."""


class TracksError(SimrigError):
    """A tracks file is missing, malformed, or does not fit the dataset it is scored against."""


class RenderPlatformError(SimrigError):
    """No offscreen OpenGL context could be made for rendering (the message names ``PYOPENGL_PLATFORM``)."""


class TrafficCrashError(SimrigError):
    """Two road users other than the ego collided in a scenario that refuses crashes (``traffic.crashes =
    "refused"``); the message names the scenario, seed, frame and vehicles."""
